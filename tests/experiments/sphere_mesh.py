"""A k-sphere as a simplicial complex, made without a solve, for the tests of k >= 3 outputs
(docs/contracts.md 4.4, docs/viewer.md): the boundary of the cube [0, g]^(k+1), each of its
2 (k + 1) facets cut into g^k small cubes and each small cube into the k! simplices of Kuhn's
triangulation (one per order of its axes: the path from its lowest to its highest corner), the
vertices pushed onto the sphere of radius r about the cube's centre. Kuhn's simplices of
neighbouring cubes, and of facets that meet, share their common faces, so the complex is a
closed k-manifold: one component, every (k-1)-face in exactly two k-simplices. Plain Python
(no numpy), for python3, pvpython and pytest alike."""

import itertools
import math


def kuhn_sphere(k, g=3, r=math.sqrt(0.5), n=None):
    """(vertices, simplices): vertices as tuples of n floats (n = k + 1 unless given larger:
    zeros after), simplices as tuples of k + 1 vertex rows."""
    n = n or k + 1
    index, vertices, simplices = {}, [], []

    def vertex(p):
        if p not in index:
            index[p] = len(vertices)
            centred = [x - g / 2 for x in p]
            length = math.sqrt(sum(x * x for x in centred))
            vertices.append(tuple(r * x / length for x in centred) + (0.0,) * (n - k - 1))
        return index[p]

    for axis in range(k + 1):
        free = [j for j in range(k + 1) if j != axis]
        for side in (0, g):
            for cube in itertools.product(range(g), repeat=k):
                for order in itertools.permutations(range(k)):
                    corner = [0] * (k + 1)
                    corner[axis] = side
                    for m, j in enumerate(free):
                        corner[j] = cube[m]
                    simplex = [vertex(tuple(corner))]
                    for m in order:
                        corner[free[m]] += 1
                        simplex.append(vertex(tuple(corner)))
                    simplices.append(tuple(simplex))
    return vertices, simplices


def ascii_ply(vertices, simplices, problem="kuhn-sphere", variables=None):
    """mesh.ply as `solve --ascii` writes it (docs/contracts.md 4.4): x y z, u0 .., and a `face`
    of k + 1 indices per simplex."""
    n = len(vertices[0])
    lines = ["ply", "format ascii 1.0", f"comment ndcontour test problem {problem}"]
    if variables:
        lines.append("comment variables " + " ".join(variables))
    lines.append(f"element vertex {len(vertices)}")
    lines += [f"property double {c}" for c in "xyz"]
    lines += [f"property double u{j}" for j in range(n)]
    lines += [f"element face {len(simplices)}", "property list uchar int vertex_indices",
              "end_header"]
    for v in vertices:
        lines.append(" ".join(repr(x) for x in (list(v[:3]) + [0.0] * (3 - min(3, n)) + list(v))))
    for s in simplices:
        lines.append(" ".join(str(i) for i in (len(s),) + tuple(s)))
    return "\n".join(lines) + "\n"
