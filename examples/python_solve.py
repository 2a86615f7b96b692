#!/usr/bin/python3
"""Solving from Python (docs/python.md): a torus in R^3 and the Clifford torus in R^4, their
meshes as numpy arrays, a residual check against the equations, and the files of `solve --out`.

Run from the checkout after scripts/build.sh:
    PYTHONPATH=build/python python3 examples/python_solve.py [OUT_DIR]
"""

import pathlib
import sys

import numpy as np

import ndcontour

root = pathlib.Path(__file__).resolve().parents[1]
out = pathlib.Path(sys.argv[1]) if len(sys.argv) > 1 else pathlib.Path("results/python-example")

# A problem file by path.
torus = ndcontour.solve(root / "experiments/problems/torus.toml", depth=5)
print(torus)
x, y, z = torus.vertices.T
residual = np.abs((x**2 + y**2 + z**2 + 1 - 0.16) ** 2 - 4 * (x**2 + y**2))
print(f"torus: {len(torus.vertices)} vertices, max |F| {residual.max():.2e}, "
      f"euler {torus.summary['mesh']['euler_characteristic']}, "
      f"certified {torus.summary['topology']['certified']}")

# A problem as a dict: the Clifford torus in R^4 (k = 2, two equations).
clifford = ndcontour.solve({
    "name": "clifford-torus",
    "variables": ["x", "y", "z", "w"],
    "domain": [[-1, 1]] * 4,
    "equations": ["x^2 + y^2 - 0.5", "z^2 + w^2 - 0.5"],
    "expect": {"components": 1, "euler_characteristic": 0},
}, depth=4)
v = clifford.vertices
print(f"clifford torus: {v.shape[0]} vertices in R^{v.shape[1]}, "
      f"max | |(x, y)| - sqrt(0.5) | {np.abs(np.hypot(v[:, 0], v[:, 1]) - 0.5**0.5).max():.2e}, "
      f"expect {clifford.summary['expect']}")

# Bad input raises ndcontour.InputError (a ValueError) with the command line's message.
try:
    ndcontour.solve(root / "experiments/problems/torus.toml", depth=0)
except ndcontour.InputError as error:
    print(f"as expected: {error}")

# The files of `ndcontour solve --out DIR`.
for path in clifford.write(str(out)):
    print("wrote", path)
