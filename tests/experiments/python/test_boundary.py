"""Topology of zero sets M that meet the boundary of the domain box (ctest "python"; issue "Sound
certificates where M meets the domain's boundary"). `solve` runs as a process, as a user runs it.

Three kinds of check, each on M ∩ box, the part of M inside the domain:
- depth consistency: seeded random dense polynomial systems (surfaces in R^3, R^4, R^5, curves
  in R^3, R^4), solved at several depths in double and once in MPFR; two certified runs of one
  system may not disagree on (components, Euler characteristic, boundary components, open ends);
- ground truth from an independent method: random surfaces in R^3 against marching cubes
  (scikit-image, Debian python3-skimage) and random curves in R^2 against its contour tracing,
  each accepted only when two grid resolutions agree; every certified run must equal it;
- constructed cases of known topology: caps cutting a corner, an edge or a face of the box, a
  thin strip along a face, arcs ending on faces; degenerate contact (M through a corner or ending
  on an edge of the box) must be uncertified or right, and tangency with the boundary must not be
  certified.

NDC_BOUNDARY_CORPUS=200 runs a larger depth-consistency corpus (depths 3..6 and MPFR at depth 3,
every class) and prints one summary line; it is skipped otherwise.

Run from the checkout (ctest sets both variables):
  NDC_BINARY=build/bin/ndcontour NDC_SOURCE_DIR=. python3 -m pytest -q tests/experiments/python/test_boundary.py
"""

import concurrent.futures
import errno
import itertools
import json
import os
import pathlib
import random
import subprocess
import time

import numpy as np
import pytest
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components
from skimage import measure  # Debian python3-skimage (scripts/setup.sh)

ROOT = pathlib.Path(os.environ.get("NDC_SOURCE_DIR", pathlib.Path(__file__).resolve().parents[3]))
BINARY = os.environ.get("NDC_BINARY", str(ROOT / "build" / "bin" / "ndcontour"))
VARIABLES = ["x", "y", "z", "w", "v"]
WORKERS = 2


# --- Problems ---------------------------------------------------------------------------------

def poly_terms(rng, n, deg, anchor=None):
    """The project's random dense polynomial generator as (exponents, coefficient) pairs: one
    coefficient gauss(0, 1) / (1 + |e|), rounded as the problem text prints it, per monomial of
    degree <= deg. With `anchor` (a point of the box) the constant term is moved so that the
    polynomial (nearly) vanishes there: every anchored system's M passes through the box."""
    terms = []
    for e in itertools.product(range(deg + 1), repeat=n):
        if sum(e) > deg:
            continue
        terms.append([e, float(f"{rng.gauss(0, 1) / (1 + sum(e)):.6f}")])
    if anchor is not None:
        value = sum(c * np.prod([a ** k for a, k in zip(anchor, e)]) for e, c in terms)
        terms[0][1] = float(f"{terms[0][1] - value:.6f}")  # terms[0] is the constant
    return terms


def poly_text(terms, vs):
    parts = []
    for e, c in terms:
        mono = "*".join(f"{v}^{k}" if k > 1 else v for v, k in zip(vs, e) if k)
        parts.append(f"({c:.6f})" + (f"*{mono}" if mono else ""))
    return " + ".join(parts)


def problem_text(name, vs, equations, domain=None):
    domain = domain or [[-1, 1]] * len(vs)
    return (f'name = "{name}"\n'
            f'variables = [{", ".join(chr(34) + v + chr(34) for v in vs)}]\n'
            f'domain = [{", ".join(f"[{a}, {b}]" for a, b in domain)}]\n'
            f'equations = [{", ".join(chr(34) + e + chr(34) for e in equations)}]\n')


# Random classes: (dimension n, number of equations n - k, degrees to draw from).
CLASSES = {
    "surface-r3": (3, 1, (2, 3, 4)),
    "surface-r4": (4, 2, (2,)),
    "surface-r5": (5, 3, (2,)),
    "curve-r3": (3, 2, (2, 3)),
    "curve-r4": (4, 3, (2,)),
}


def random_system(kind, seed):
    """Returns (problem text, per-equation term lists) of one seeded random system on [-1, 1]^n.
    Four in five systems are anchored at a random point of [-0.8, 0.8]^n (M meets the box); the
    others are the plain generator's (some of those miss the box, which is kept on purpose)."""
    n, m, degrees = CLASSES[kind]
    rng = random.Random(seed)
    vs = VARIABLES[:n]
    anchor = [rng.uniform(-0.8, 0.8) for _ in vs] if rng.random() < 0.8 else None
    systems = [poly_terms(rng, n, rng.choice(degrees), anchor) for _ in range(m)]
    text = problem_text(f"{kind}-{seed}", vs, [poly_text(t, vs) for t in systems])
    return text, systems


# --- Running the CLI --------------------------------------------------------------------------

def run_solve(path, depth, *extra, timeout=900):
    """One `ndcontour solve --json` run: (summary or None, error text or None). Retries while the
    binary is being rebuilt (text file busy, missing for a moment)."""
    command = [BINARY, "solve", str(path), "--depth", str(depth), "--json", "--threads", "1",
               *extra]
    for attempt in range(30):
        try:
            r = subprocess.run(command, capture_output=True, text=True, timeout=timeout)
        except OSError as error:
            if error.errno in (errno.ETXTBSY, errno.ENOENT, errno.EACCES) and attempt < 29:
                time.sleep(2)
                continue
            raise
        except subprocess.TimeoutExpired:
            return None, f"no answer in {timeout} s"
        if r.returncode in (126, 127) or "Text file busy" in r.stderr:
            time.sleep(2)
            continue
        if r.returncode != 0:
            return None, f"exit status {r.returncode}: {r.stderr.strip()}"
        return json.loads(r.stdout), None
    return None, "the binary could not be run (being rebuilt?)"


def topology(summary):
    mesh = summary["mesh"]
    return (mesh["components"], mesh["euler_characteristic"], mesh["boundary_components"],
            mesh["open_ends"])


TOPOLOGY_FIELDS = "(components, euler, boundary_components, open_ends)"


def expected_cost(job):
    """A rough order of a job's cost, so that the long runs start first: MPFR, then more
    variables, then deeper."""
    path, depth, extra = job
    variables = pathlib.Path(path).read_text().split("variables", 1)[1].split("]", 1)[0]
    return ("mpfr" in extra, variables.count(","), depth)


def solve_all(jobs):
    """jobs: (path, depth, extra args); returns one (summary, error) per job, in order, on two
    workers of one thread each, the long runs first."""
    order = sorted(range(len(jobs)), key=lambda i: expected_cost(jobs[i]), reverse=True)
    with concurrent.futures.ThreadPoolExecutor(WORKERS) as pool:
        done = dict(zip(order, pool.map(lambda i: run_solve(jobs[i][0], jobs[i][1], *jobs[i][2]),
                                        order)))
    return [done[i] for i in range(len(jobs))]


def run_label(depth, extra):
    return f"depth {depth}" + (" mpfr" if "mpfr" in extra else "")


def describe(path, runs):
    """The problem file's text and every run's result, for a failure message."""
    lines = [f"--- {path}", pathlib.Path(path).read_text().rstrip()]
    for (depth, extra), (summary, error) in runs:
        if error:
            lines.append(f"  {run_label(depth, extra)}: ERROR {error}")
        else:
            lines.append(f"  {run_label(depth, extra)}: {TOPOLOGY_FIELDS} = {topology(summary)}, "
                         f"certified = {summary['topology']['certified']}"
                         + (f" ({summary['topology']['reason']})"
                            if summary['topology']['reason'] else ""))
    return "\n".join(lines)


# --- Depth consistency --------------------------------------------------------------------------

def depth_consistency(tmp_path, plan, depths, mpfr_depth):
    """plan: (kind, seeds, with_mpfr). Solves every system at every depth in double and, where
    with_mpfr, once in MPFR at mpfr_depth. Returns (report line, failure texts)."""
    systems = []
    for kind, seeds, with_mpfr in plan:
        for seed in seeds:
            text, _ = random_system(kind, seed)
            path = tmp_path / f"{kind}-{seed}.toml"
            path.write_text(text)
            settings = [(d, ()) for d in depths]
            if with_mpfr:
                settings.append((mpfr_depth, ("--scalar", "mpfr")))
            systems.append((path, settings))
    jobs = [(path, d, extra) for path, settings in systems for d, extra in settings]
    results = iter(solve_all(jobs))
    failures, contradicting, empty, meeting_boundary = [], 0, 0, 0
    runs = certified = 0
    for path, settings in systems:
        outcome = [(setting, next(results)) for setting in settings]
        runs += len(outcome)
        found = {topology(s) for _, (s, e) in outcome if s and s["topology"]["certified"]}
        certified += sum(1 for _, (s, e) in outcome if s and s["topology"]["certified"])
        errors = [e for _, (s, e) in outcome if e]
        if all(s and topology(s)[0] == 0 for _, (s, e) in outcome):
            empty += 1
        if any(s and (topology(s)[2] or topology(s)[3]) for _, (s, e) in outcome):
            meeting_boundary += 1
        if len(found) > 1 or errors:
            contradicting += len(found) > 1
            why = "certified runs disagree" if len(found) > 1 else "a run failed"
            failures.append(f"{why}:\n{describe(path, outcome)}")
    report = (f"{len(systems)} systems ({meeting_boundary} meeting the boundary, {empty} empty at "
              f"every run), {contradicting} contradicting systems, {certified}/{runs} certified "
              f"runs / runs")
    return report, failures


def test_random_systems_agree_across_depths_and_scalars(tmp_path):
    # MPFR in R^5 costs 45-110 s a run at depth 3: only the corpus below runs it.
    plan = [("surface-r3", range(1000, 1008), True),
            ("surface-r4", range(2000, 2003), True),
            ("surface-r5", range(3000, 3002), False),
            ("curve-r3", range(4000, 4005), True),
            ("curve-r4", range(5000, 5004), True)]
    report, failures = depth_consistency(tmp_path, plan, depths=(3, 4, 5), mpfr_depth=3)
    print(report)
    assert not failures, (f"{report}; {len(failures)} systems fail, fields {TOPOLOGY_FIELDS}\n"
                          + "\n".join(failures))


CORPUS = int(os.environ.get("NDC_BOUNDARY_CORPUS", "0") or 0)


@pytest.mark.skipif(CORPUS <= 0, reason="set NDC_BOUNDARY_CORPUS=200 for the larger corpus")
def test_corpus_agrees_across_depths_and_scalars(tmp_path):
    # CORPUS systems, the classes in turn, depths 3..6 in double and MPFR at depth 3 for each.
    kinds = list(CLASSES)
    plan = [(kinds[i % len(kinds)], [100000 + i], True) for i in range(CORPUS)]
    started = time.monotonic()
    report, failures = depth_consistency(tmp_path, plan, depths=(3, 4, 5, 6), mpfr_depth=3)
    line = f"boundary corpus: {report} ({time.monotonic() - started:.0f} s)"
    print(line)
    assert not failures, (f"{line}; {len(failures)} systems fail, fields {TOPOLOGY_FIELDS}\n"
                          + "\n".join(failures))


# --- Ground truth: marching cubes in R^3, contour tracing in R^2 --------------------------------

def evaluate(terms, axes):
    """The polynomial on the tensor grid of the 1-d sample arrays `axes` (index order), as
    sum_a axes[0]^a * Q_a(other axes), Q_a evaluated the same way on the smaller grid."""
    if not axes:
        return np.float64(sum(c for _, c in terms))
    rest = {}
    for e, c in terms:
        rest.setdefault(e[0], []).append((e[1:], c))
    shape = (-1,) + (1,) * (len(axes) - 1)
    value = 0.0
    for a, part in rest.items():
        value = value + (axes[0] ** a).reshape(shape) * evaluate(part, axes[1:])
    return np.broadcast_to(value, tuple(len(x) for x in axes))


def components_of_graph(count, edges):
    if count == 0:
        return 0
    graph = coo_matrix((np.ones(len(edges)), (edges[:, 0], edges[:, 1])), shape=(count, count))
    return connected_components(graph, directed=False)[0]


def marching_cubes_topology(terms, samples):
    """(components, Euler characteristic, boundary components) of the marching-cubes mesh of
    {F = 0} ∩ [-1, 1]^3 on samples^3 points: the mesh ends on the box, as M ∩ box does."""
    axis = np.linspace(-1.0, 1.0, samples)
    values = evaluate(terms, [axis] * 3)
    if values.min() >= 0 or values.max() <= 0:
        return (0, 0, 0)
    vertices, faces, _, _ = measure.marching_cubes(values, 0.0)
    # Merge coincident vertices (index coordinates, to 1e-4 of a grid step; < 2^21 each), drop
    # faces that collapse and repeated faces.
    keys = np.round(vertices * 1e4).astype(np.int64)
    keys = (keys[:, 0] << 42) | (keys[:, 1] << 21) | keys[:, 2]
    _, inverse = np.unique(keys, return_inverse=True)
    faces = np.sort(inverse.ravel()[faces], axis=1)
    faces = faces[(faces[:, 0] != faces[:, 1]) & (faces[:, 1] != faces[:, 2])]
    used, faces = np.unique(faces, return_inverse=True)
    faces = faces.reshape(-1, 3).astype(np.int64)
    count = len(used)
    faces = faces[np.unique((faces[:, 0] * count + faces[:, 1]) * count + faces[:, 2],
                            return_index=True)[1]]
    edges = np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [0, 2]]])
    codes, uses = np.unique(edges[:, 0] * count + edges[:, 1], return_counts=True)
    unique_edges = np.stack([codes // count, codes % count], axis=1)
    components = components_of_graph(count, unique_edges)
    euler = count - len(unique_edges) + len(faces)
    boundary = unique_edges[uses == 1]
    boundary_vertices, boundary = np.unique(boundary, return_inverse=True)
    boundary_components = components_of_graph(len(boundary_vertices), boundary.reshape(-1, 2))
    return (int(components), int(euler), int(boundary_components))


def contour_topology(terms, samples):
    """(components, Euler characteristic, open ends) of {F = 0} ∩ [-1, 1]^2 traced on samples^2
    points: a contour that reaches the grid's border is an arc (two ends, Euler 1), the others
    are closed (Euler 0)."""
    axis = np.linspace(-1.0, 1.0, samples)
    values = evaluate(terms, [axis] * 2)
    if values.min() >= 0 or values.max() <= 0:
        return (0, 0, 0)
    contours = measure.find_contours(values, 0.0)
    arcs = sum(1 for c in contours if not np.allclose(c[0], c[-1]))
    return (len(contours), arcs, 2 * arcs)


def ground_truth_check(tmp_path, kind_name, n, seeds, degrees, truth_of, resolutions, depths, key):
    """Random single equations in n variables on [-1, 1]^n; the truth from truth_of at two
    resolutions (a system where they differ is skipped as near-degenerate), then ndcontour at
    `depths`; every certified run's key(summary) must equal the truth."""
    vs = VARIABLES[:n]
    cases = []
    for seed in seeds:
        rng = random.Random(seed)
        anchor = [rng.uniform(-0.8, 0.8) for _ in vs] if rng.random() < 0.8 else None
        terms = poly_terms(rng, n, rng.choice(degrees), anchor)
        path = tmp_path / f"{kind_name}-{seed}.toml"
        path.write_text(problem_text(f"{kind_name}-{seed}", vs, [poly_text(terms, vs)]))
        cases.append((path, terms))
    with concurrent.futures.ThreadPoolExecutor(WORKERS) as pool:
        truths = list(pool.map(lambda case: [truth_of(case[1], r) for r in resolutions], cases))
    accepted = [(path, t[0]) for (path, _), t in zip(cases, truths) if len(set(t)) == 1]
    skipped = [(path, t) for (path, _), t in zip(cases, truths) if len(set(t)) > 1]
    jobs = [(path, d, ()) for path, _ in accepted for d in depths]
    results = iter(solve_all(jobs))
    failures, runs, certified, meeting = [], 0, 0, 0
    for path, truth in accepted:
        outcome = [((d, ()), next(results)) for d in depths]
        runs += len(outcome)
        certified += sum(1 for _, (s, e) in outcome if s and s["topology"]["certified"])
        meeting += truth[-1] > 0
        wrong = [1 for _, (s, e) in outcome
                 if e or (s["topology"]["certified"] and key(s) != truth)]
        if wrong:
            failures.append(f"truth {truth}:\n{describe(path, outcome)}")
    report = (f"{len(cases)} systems, {len(accepted)} with a ground truth ({meeting} meeting the "
              f"boundary), {len(skipped)} skipped as near-degenerate "
              f"({', '.join(f'{p.name} {t}' for p, t in skipped) or '-'}), "
              f"{certified}/{runs} certified runs / runs, {len(failures)} systems wrong")
    return report, failures, len(accepted)


def sphere_terms(radius, centre):
    """|u - centre|^2 - radius^2 as (exponents, coefficient) pairs."""
    n = len(centre)
    unit = [tuple(int(i == j) for i in range(n)) for j in range(n)]
    terms = [[tuple(2 * k for k in unit[j]), 1.0] for j in range(n)]
    terms += [[unit[j], -2.0 * c] for j, c in enumerate(centre)]
    return terms + [[(0,) * n, sum(c * c for c in centre) - radius * radius]]


def test_the_ground_truth_methods_on_known_shapes():
    # The two reference methods themselves, on M ∩ box of known topology.
    cases = [(sphere_terms(0.5, (1, 1, 1)), (1, 1, 1)),       # cap at a corner: a disk
             (sphere_terms(0.4, (1, 1, 0)), (1, 1, 1)),       # quarter sphere across an edge
             (sphere_terms(0.5, (0.1, 0.2, 0)), (1, 2, 0)),   # a whole sphere inside
             ([[(2, 0, 0), 1.0], [(0, 2, 0), 1.0], [(0, 0, 0), -0.25]], (1, 0, 2)),  # open cylinder
             ([[(2, 0, 0), 1.0], [(0, 0, 0), -0.25]], (2, 2, 2))]  # two planes x = +-0.5
    for terms, truth in cases:
        assert marching_cubes_topology(terms, 121) == truth, (terms, truth)
    assert contour_topology(sphere_terms(0.5, (0, 0)), 1001) == (1, 0, 0)
    assert contour_topology(sphere_terms(0.5, (1, 0)), 1001) == (1, 1, 2)
    assert contour_topology([[(2, 0), 1.0], [(0, 0), -0.25]], 1001) == (2, 2, 4)


def test_random_surfaces_in_r3_match_marching_cubes(tmp_path):
    fields = "(components, euler, boundary_components)"
    report, failures, accepted = ground_truth_check(
        tmp_path, "mc-surface-r3", 3, range(6000, 6030), (2, 3, 4), marching_cubes_topology,
        resolutions=(121, 201), depths=(3, 4, 5),
        key=lambda s: topology(s)[:3])
    print(report)
    assert not failures, (f"{report}; certified runs against marching cubes, fields {fields}\n"
                          + "\n".join(failures))
    assert accepted >= 20, f"too few systems with a ground truth: {report}"


def test_random_curves_in_r2_match_contour_tracing(tmp_path):
    fields = "(components, euler, open_ends)"
    report, failures, accepted = ground_truth_check(
        tmp_path, "contour-curve-r2", 2, range(7000, 7040), (2, 3, 4), contour_topology,
        resolutions=(1001, 1601), depths=(3, 4, 5),
        key=lambda s: (topology(s)[0], topology(s)[1], topology(s)[3]))
    print(report)
    assert not failures, (f"{report}; certified runs against contour tracing, fields {fields}\n"
                          + "\n".join(failures))
    assert accepted >= 28, f"too few systems with a ground truth: {report}"


# --- Constructed cases of known topology --------------------------------------------------------

XYZ = ["x", "y", "z"]
DEPTHS = (3, 4, 5, 6)

# name, variables, equations, (components, euler, boundary_components, open_ends) of M ∩ box.
TRANSVERSAL = [
    ("cap-at-a-corner", XYZ, ["(x - 1)^2 + (y - 1)^2 + (z - 1)^2 - 0.25"], (1, 1, 1, 0)),
    # A quarter sphere: a disk whose boundary runs over two faces through two points of an edge.
    ("cap-across-an-edge", XYZ, ["(x - 1)^2 + (y - 1)^2 + z^2 - 0.16"], (1, 1, 1, 0)),
    ("cap-on-a-face", XYZ, ["(x - 1.1)^2 + y^2 + z^2 - 0.09"], (1, 1, 1, 0)),
    # The cylinder's piece with 0.95 <= x <= 1: an arc in (x, z) times [-1, 1] in y, a disk.
    ("strip-along-a-face", XYZ, ["(x - 1.15)^2 + z^2 - 0.04"], (1, 1, 1, 0)),
    # A half circle in the plane z = 0 with both ends on the face x = 1.
    ("arc-ending-on-a-face", XYZ, ["(x - 1)^2 + y^2 + z^2 - 0.25", "z"], (1, 1, 0, 2)),
    # The circle of radius 1.3 in x + y + z = 0 leaves the hexagon (x + y + z = 0) ∩ box near each
    # of its 6 corners: 6 arcs, each from one face to another.
    ("six-arcs-on-faces", XYZ, ["x^2 + y^2 + z^2 - 1.69", "x + y + z"], (6, 6, 0, 12)),
    ("arc-ending-on-a-side", ["x", "y"], ["(x - 1)^2 + y^2 - 0.25"], (1, 1, 0, 2)),
]

# M meets a corner or an edge of the box (non-generic contact): uncertified or right.
DEGENERATE = [
    ("line-through-two-corners", XYZ, ["x - y", "y - z"], (1, 1, 0, 2)),
    # x + y - z = 1 meets the box in the triangle of the corners (1,1,1), (1,-1,-1), (-1,1,-1).
    ("plane-through-three-corners", XYZ, ["x + y - z - 1"], (1, 1, 1, 0)),
    # A half circle in the plane x = y, centred on the box's edge x = y = 1, ending on that edge.
    ("arc-ending-on-an-edge", XYZ, ["(x - 1)^2 + (y - 1)^2 + z^2 - 0.25", "x - y"], (1, 1, 0, 2)),
    ("diagonal-through-two-corners-r2", ["x", "y"], ["x - y"], (1, 1, 0, 2)),
    # The unit sphere touches each face of [-1, 1]^3 at one point; M ∩ box is the whole sphere.
    ("sphere-tangent-to-every-face", XYZ, ["x^2 + y^2 + z^2 - 1"], (1, 2, 0, 0)),
]

# Tangency with the boundary or M through a corner: not certified (the certificate cannot
# prove the topology there).
NOT_CERTIFIED = [
    ("sphere-tangent-to-every-face", XYZ, ["x^2 + y^2 + z^2 - 1"]),
    # From outside: M ∩ box is the one point (0, 0, 1).
    ("sphere-touching-a-face-from-outside", XYZ, ["x^2 + y^2 + (z - 1.5)^2 - 0.25"]),
    ("line-through-two-corners", XYZ, ["x - y", "y - z"]),
    ("plane-through-three-corners", XYZ, ["x + y - z - 1"]),
]


def solve_constructed(tmp_path, name, vs, equations):
    path = tmp_path / f"{name}.toml"
    path.write_text(problem_text(name, vs, equations))
    outcome = list(zip([(d, ()) for d in DEPTHS], solve_all([(path, d, ()) for d in DEPTHS])))
    return path, outcome


@pytest.mark.parametrize("name,vs,equations,truth", TRANSVERSAL, ids=[c[0] for c in TRANSVERSAL])
def test_transversal_contact_with_the_boundary(tmp_path, name, vs, equations, truth):
    path, outcome = solve_constructed(tmp_path, name, vs, equations)
    bad = [label for label, (s, e) in outcome
           if e or (s["topology"]["certified"] and topology(s) != truth)]
    assert not bad, (f"{name}: certified runs must give {TOPOLOGY_FIELDS} = {truth}; wrong at "
                     f"{bad}\n{describe(path, outcome)}")


@pytest.mark.parametrize("name,vs,equations,truth", DEGENERATE, ids=[c[0] for c in DEGENERATE])
def test_degenerate_contact_is_uncertified_or_right(tmp_path, name, vs, equations, truth):
    path, outcome = solve_constructed(tmp_path, name, vs, equations)
    bad = [label for label, (s, e) in outcome
           if e or (s["topology"]["certified"] and topology(s) != truth)]
    assert not bad, (f"{name}: certified runs must give {TOPOLOGY_FIELDS} = {truth}; wrong at "
                     f"{bad}\n{describe(path, outcome)}")


@pytest.mark.parametrize("name,vs,equations", NOT_CERTIFIED, ids=[c[0] for c in NOT_CERTIFIED])
def test_tangency_and_corner_passages_are_not_certified(tmp_path, name, vs, equations):
    path, outcome = solve_constructed(tmp_path, name, vs, equations)
    certified = [label for label, (s, e) in outcome if not e and s["topology"]["certified"]]
    errors = [label for label, (s, e) in outcome if e]
    assert not errors, f"{name}: runs failed at {errors}\n{describe(path, outcome)}"
    assert not certified, (f"{name}: M is tangent to the box's boundary or passes through a "
                           f"corner, yet certified at {certified}\n{describe(path, outcome)}")
