#!/usr/bin/python3
"""Independent error and topology of a mesh of a peer-benchmark problem (bench/, docs/performance.md).

Usage: bench/measure.py PROBLEM MESH.ply [--spacing H]   (sample spacing on M, default 0.02)

Reads an ASCII or binary_little_endian PLY (ndcontour's mesh.ply, or the output of
bench/cgal_torus and bench/gudhi_trace: coordinates u0..u{n-1}, or x y z when there are no u's;
faces or edges), and prints one JSON line with

* the topology: vertices, simplices, components, Euler characteristic, boundary and
  non-manifold edges (surfaces), vertices of degree other than 2 (curves), or boundary and
  non-manifold triangles and the Betti numbers over Z/2 and over Q (3-manifolds, k = 3: a
  tetrahedron `face` of 4 vertices; the Betti numbers of a closed one, every triangle in two
  tetrahedra, by collapsing it to a small complex whose boundary ranks are then computed);
* for the problems whose distance function is known in closed form (torus,
  clifford-torus-rotated, sphere-r5, flat-torus-r6, circle-r8): the two-sided Hausdorff distance
  between the mesh and the true manifold M. Mesh -> M: the exact distance to M of the vertices and
  of a barycentric grid on every simplex (4 steps per triangle edge, 8 per segment). M -> mesh:
  the exact point-to-triangle (point-to-segment) distance to the mesh of a dense sample of M
  (spacing about 0.02: it finds missing or misplaced pieces of the mesh; the chord error between
  the samples is what the mesh -> M side measures). For the 3-manifolds (sphere3-r5, sphere3-r6,
  s1xs2-r5, flat-3torus-r6, o3-r9) mesh -> M uses the vertices and a barycentric grid of 3 steps
  per tetrahedron edge, and M -> mesh a sample of M of spacing about 0.08 (pseudo-random with a
  fixed seed, or a grid) with the exact distance to the tetrahedra around the 32 mesh vertices
  nearest to each sample point (an upper bound of the distance to the mesh, exact unless the
  nearest tetrahedron has none of those vertices; on the 3-sphere meshes 16 already give the
  value of 48);
* for genus2 (no closed-form distance): the maximum of |F| / |grad F| (the first-order distance)
  over the same points of the mesh.

"error" is the Hausdorff distance where it is known and the residual otherwise.
"""

import json
import math
import sys

import numpy as np

# --- PLY ---------------------------------------------------------------------------------------

_TYPES = {
    "char": "i1", "int8": "i1", "uchar": "u1", "uint8": "u1",
    "short": "i2", "int16": "i2", "ushort": "u2", "uint16": "u2",
    "int": "i4", "int32": "i4", "uint": "u4", "uint32": "u4",
    "float": "f4", "float32": "f4", "double": "f8", "float64": "f8",
}


def read_ply(path):
    """Elements of an ASCII or binary_little_endian PLY: {name: {property: array or list}}."""
    with open(path, "rb") as f:
        data = f.read()
    end = data.find(b"end_header")
    if not data.startswith(b"ply") or end < 0:
        raise ValueError(f"{path}: not a PLY file")
    body = end + len(b"end_header")
    body = data.index(b"\n", body) + 1
    fmt = None
    elements = []  # (name, count, [(prop, type) or (prop, (count type, item type))])
    for line in data[:end].decode("ascii", "replace").splitlines():
        words = line.split()
        if not words:
            continue
        if words[0] == "format":
            fmt = words[1]
        elif words[0] == "element":
            elements.append((words[1], int(words[2]), []))
        elif words[0] == "property":
            if words[1] == "list":
                elements[-1][2].append((words[4], (_TYPES[words[2]], _TYPES[words[3]])))
            else:
                elements[-1][2].append((words[2], _TYPES[words[1]]))
    out = {}
    if fmt == "ascii":
        tokens = data[body:].split()
        pos = 0
        for name, count, props in elements:
            if all(not isinstance(t, tuple) for _, t in props):
                width = len(props)
                block = np.array(tokens[pos:pos + width * count], dtype=float).reshape(count, width)
                pos += width * count
                out[name] = {p: block[:, i] for i, (p, _) in enumerate(props)}
                continue
            columns = {p: [] for p, _ in props}
            for _ in range(count):
                for p, t in props:
                    if isinstance(t, tuple):
                        m = int(tokens[pos])
                        columns[p].append([int(x) for x in tokens[pos + 1:pos + 1 + m]])
                        pos += 1 + m
                    else:
                        columns[p].append(float(tokens[pos]))
                        pos += 1
            out[name] = {p: (v if isinstance(dict(props)[p], tuple) else np.array(v))
                         for p, v in columns.items()}
    elif fmt == "binary_little_endian":
        pos = body
        for name, count, props in elements:
            if all(not isinstance(t, tuple) for _, t in props):
                dtype = np.dtype([(p, "<" + t) for p, t in props])
                block = np.frombuffer(data, dtype=dtype, count=count, offset=pos)
                pos += dtype.itemsize * count
                out[name] = {p: block[p].astype(float) for p, _ in props}
                continue
            if len(props) == 1 and count > 0:  # faces: try lists of one length (triangles)
                p, (ct, it) = props[0]
                m = int(np.frombuffer(data, dtype="<" + ct, count=1, offset=pos)[0])
                dtype = np.dtype([("n", "<" + ct), ("i", "<" + it, (m,))])
                if pos + dtype.itemsize * count <= len(data):
                    block = np.frombuffer(data, dtype=dtype, count=count, offset=pos)
                    if (block["n"] == m).all():
                        out[name] = {p: block["i"].tolist()}
                        pos += dtype.itemsize * count
                        continue
            columns = {p: [] for p, _ in props}
            for _ in range(count):
                for p, t in props:
                    if isinstance(t, tuple):
                        ct, it = np.dtype("<" + t[0]), np.dtype("<" + t[1])
                        m = int(np.frombuffer(data, dtype=ct, count=1, offset=pos)[0])
                        pos += ct.itemsize
                        columns[p].append(
                            np.frombuffer(data, dtype=it, count=m, offset=pos).tolist())
                        pos += it.itemsize * m
                    else:
                        dt = np.dtype("<" + t)
                        columns[p].append(float(np.frombuffer(data, dtype=dt, count=1,
                                                              offset=pos)[0]))
                        pos += dt.itemsize
            out[name] = columns
    else:
        raise ValueError(f"{path}: unsupported PLY format {fmt}")
    return out


def read_mesh(path, n, k=2):
    """Vertices (V x n) and simplices (S x 2 segments, S x 3 triangles with polygons fanned, or
    for k = 3 S x 4 tetrahedra, the `face` lists of 4 vertices)."""
    ply = read_ply(path)
    vert = ply["vertex"]
    names = [f"u{j}" for j in range(n)] if "u0" in vert else ["x", "y", "z"][:n]
    points = np.column_stack([np.asarray(vert[c], dtype=float) for c in names])
    if k == 3:
        face = ply.get("face", {})
        lists = face.get("vertex_indices", face.get("vertex_index", []))
        return points, np.array(lists, dtype=np.int64).reshape(-1, 4)
    if "face" in ply and len(next(iter(ply["face"].values()), [])) > 0:
        face = ply["face"]
        lists = face.get("vertex_indices", face.get("vertex_index"))
        tris = [(f[0], f[i], f[i + 1]) for f in lists for i in range(1, len(f) - 1)]
        return points, np.array(tris, dtype=np.int64).reshape(-1, 3)
    if "edge" in ply:
        e = ply["edge"]
        return points, np.column_stack([np.asarray(e["vertex1"]), np.asarray(e["vertex2"])]
                                       ).astype(np.int64).reshape(-1, 2)
    return points, np.zeros((0, 3), dtype=np.int64)


# --- Problems: exact distance to M, samples of M, or the residual ------------------------------


def _rotation6():
    def g(i, j, c, s):
        m = np.eye(6)
        m[i, i] = m[j, j] = c
        m[i, j], m[j, i] = -s, s
        return m
    return g(0, 3, .6, .8) @ g(1, 4, .8, .6) @ g(2, 5, .6, .8) @ g(3, 1, .8, .6) @ g(4, 2, .6, .8)


def _clifford(r):
    """Clifford torus q1^2+q2^2 = q3^2+q4^2 = 1/2, q5.. = 0 in q = R x (flat torus, area 2 pi^2)."""
    a = math.sqrt(0.5)

    def dist(x):
        q = x @ r.T
        d2 = (np.hypot(q[:, 0], q[:, 1]) - a) ** 2 + (np.hypot(q[:, 2], q[:, 3]) - a) ** 2
        if q.shape[1] > 4:
            d2 += (q[:, 4:] ** 2).sum(axis=1)
        return np.sqrt(d2)

    def samples(spacing):
        m = int(math.ceil(2 * math.pi * a / spacing))
        t = np.linspace(0, 2 * math.pi, m, endpoint=False)
        u, v = np.meshgrid(t, t, indexing="ij")
        q = np.zeros((m * m, r.shape[0]))
        q[:, 0], q[:, 1] = a * np.cos(u.ravel()), a * np.sin(u.ravel())
        q[:, 2], q[:, 3] = a * np.cos(v.ravel()), a * np.sin(v.ravel())
        return q @ r  # x = R^T q

    return dist, samples


def _flat_sphere(c, radius, m, d):
    """The sphere |x - c| = radius cut by the flat M x + d = 0: a round sphere of radius rho
    about the foot c0 of c on the flat, in the span of `basis` (orthonormal rows, the flat's
    directions); returns c0, rho, basis and the distance to it of each row of x."""
    c, m, d = np.asarray(c, float), np.atleast_2d(np.asarray(m, float)), np.asarray(d, float)
    c0 = c - m.T @ np.linalg.solve(m @ m.T, m @ c + d)
    rho = math.sqrt(radius * radius - (c - c0) @ (c - c0))
    _, _, vt = np.linalg.svd(m)
    basis = vt[m.shape[0]:]

    def dist(x):
        y = x - c0
        inplane = y @ basis.T
        h2 = (y ** 2).sum(axis=1) - (inplane ** 2).sum(axis=1)
        return np.sqrt(np.maximum(h2, 0) + (np.linalg.norm(inplane, axis=1) - rho) ** 2)

    return c0, rho, basis, dist


def _sphere_section(m, d):
    """Unit sphere cut by M x + d = 0: a sphere of radius rho about c0 in the flat."""
    m = np.atleast_2d(np.asarray(m, float))
    c0, rho, basis, dist = _flat_sphere(np.zeros(m.shape[1]), 1.0, m, d)
    k = basis.shape[0] - 1  # dimension of the sphere

    def samples(spacing):
        if k == 1:
            t = np.linspace(0, 2 * math.pi, int(math.ceil(20 * math.pi * rho / spacing)),
                            endpoint=False)
            u = np.column_stack([np.cos(t), np.sin(t)])
        else:  # Fibonacci points on S^2
            count = int(math.ceil(4 * math.pi * rho * rho / spacing ** 2))
            i = np.arange(count) + 0.5
            z = 1 - 2 * i / count
            phi = math.pi * (1 + 5 ** 0.5) * i
            s = np.sqrt(1 - z * z)
            u = np.column_stack([s * np.cos(phi), s * np.sin(phi), z])
        return c0 + rho * u @ basis

    return dist, samples


def _ball_section(c, radius, m, d, seed):
    """The sphere |x - c| = radius cut by the flat M x + d = 0 (k = 3): a round 3-sphere of
    radius rho about the foot c0 of c on the flat; samples pseudo-random (seed) on it."""
    c0, rho, basis, dist = _flat_sphere(c, radius, m, d)

    def samples(spacing):
        count = int(math.ceil(2 * math.pi ** 2 * rho ** 3 / spacing ** 3))
        u = np.random.default_rng(seed).standard_normal((count, basis.shape[0]))
        u /= np.linalg.norm(u, axis=1)[:, None]
        return c0 + rho * u @ basis

    return dist, samples


def _sphere_product(blocks, c, radii):
    """Round spheres |x_I - c_I| = r_I in consecutive blocks I of coordinates (their product):
    the distance is the root of the sum of the blocks' squared distances; samples a grid of
    circles' angles and Fibonacci points on 2-spheres."""
    c = np.asarray(c, float)
    starts = np.cumsum([0] + list(blocks))

    def dist(x):
        d2 = 0
        for b, r in enumerate(radii):
            y = x[:, starts[b]:starts[b + 1]] - c[starts[b]:starts[b + 1]]
            d2 = d2 + (np.linalg.norm(y, axis=1) - r) ** 2
        return np.sqrt(d2)

    def factor(size, r, spacing):
        if size == 2:
            t = np.linspace(0, 2 * math.pi, int(math.ceil(2 * math.pi * r / spacing)),
                            endpoint=False)
            return r * np.column_stack([np.cos(t), np.sin(t)])
        count = int(math.ceil(4 * math.pi * r * r / spacing ** 2))
        i = np.arange(count) + 0.5
        z = 1 - 2 * i / count
        phi = math.pi * (1 + 5 ** 0.5) * i
        w = np.sqrt(1 - z * z)
        return r * np.column_stack([w * np.cos(phi), w * np.sin(phi), z])

    def samples(spacing):
        out = np.zeros((1, 0))
        for size, r in zip(blocks, radii):
            f = factor(size, r, spacing)
            out = np.column_stack([np.repeat(out, len(f), axis=0), np.tile(f, (len(out), 1))])
        return out + c

    return dist, samples


def _orthogonal_group():
    """O(3) in R^9 (row by row): the distance of X is |Sigma - I| over its singular values
    (the nearest orthogonal matrix is U V^T); samples: rotations from pseudo-random unit
    quaternions and their negatives (the det -1 component)."""
    def dist(x):
        sv = np.linalg.svd(x.reshape(-1, 3, 3), compute_uv=False)
        return np.sqrt(((sv - 1) ** 2).sum(axis=1))

    def samples(spacing):
        # Each component is RP^3, a 3-sphere of radius 2 sqrt(2) mod +-1 in R^9: volume 16 sqrt(2) pi^2.
        count = int(math.ceil(16 * math.sqrt(2) * math.pi ** 2 / spacing ** 3))
        q = np.random.default_rng(9).standard_normal((count, 4))
        q /= np.linalg.norm(q, axis=1)[:, None]
        w, x, y, z = q.T
        r = np.column_stack([1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w),
                             2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w),
                             2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)])
        return np.concatenate([r, -r])

    return dist, samples


_C6 = [0.0317, -0.0211, 0.0143, -0.0378, 0.0259, -0.0096]


def _torus():
    def dist(x):
        return np.abs(np.hypot(np.hypot(x[:, 0], x[:, 1]) - 1, x[:, 2]) - 0.4)

    def samples(spacing):
        m1 = int(math.ceil(2 * math.pi * 1.4 / spacing))
        m2 = int(math.ceil(2 * math.pi * 0.4 / spacing))
        u, v = np.meshgrid(np.linspace(0, 2 * math.pi, m1, endpoint=False),
                           np.linspace(0, 2 * math.pi, m2, endpoint=False), indexing="ij")
        u, v = u.ravel(), v.ravel()
        rr = 1 + 0.4 * np.cos(v)
        return np.column_stack([rr * np.cos(u), rr * np.sin(u), 0.4 * np.sin(v)])

    return dist, samples


def _genus2_residual(x):
    """|F| / |grad F| for F = f^2 + z^2 - 0.01, f = (x^2 + y^2)^2 - x^2 + y^2."""
    px, py, pz = x[:, 0], x[:, 1], x[:, 2]
    r = px * px + py * py
    f = r * r - px * px + py * py
    F = f * f + pz * pz - 0.01
    g = np.column_stack([2 * f * (4 * px * r - 2 * px), 2 * f * (4 * py * r + 2 * py), 2 * pz])
    return np.abs(F) / np.maximum(np.linalg.norm(g, axis=1), 1e-300)


PROBLEMS = {
    "torus": (3, 2, _torus()),
    "clifford-torus-rotated": (4, 2, _clifford(0.5 * np.array(
        [[1, 1, 1, 1], [1, -1, 1, -1], [1, 1, -1, -1], [1, -1, -1, 1]], float))),
    "sphere-r5": (5, 2, _sphere_section([[1, 1, -1, 0, .5], [0, 1, .5, -1, 1]], [.1, -.05])),
    "flat-torus-r6": (6, 2, _clifford(_rotation6())),
    "circle-r8": (8, 1, _sphere_section(
        [[1, 1, -1, 0, .5, 0, 0, .25], [0, 1, .5, -1, 1, .25, 0, 0], [.5, 0, 1, 1, -1, 1, 0, 0],
         [1, -.5, 0, 1, .25, -1, .5, 0], [0, 0, 1, 0, .5, 1, -1, 1],
         [.25, 1, 0, .5, 0, 0, 1, -1]], [.1, -.05, .15, -.1, .05, -.1])),
    "genus2": (3, 2, None),
    # k = 3: the problem files experiments/problems/sphere3-r5.toml .. o3-r9.toml.
    "sphere3-r5": (5, 3, _ball_section(
        _C6[:5], 0.93, [[-0.010174, 0.587131, -0.532017, 0.540751, 0.282348]], [0.0334464], 5)),
    "sphere3-r6": (6, 3, _ball_section(
        _C6, 0.93, [[0.824223, -0.437238, -0.310599, 0.114575, -0.0962254, -0.103056],
                    [0.187423, 0.62032, -0.347973, 0.532667, 0.112204, 0.40332]],
        [-0.0250782, 0.0332241], 6)),
    "s1xs2-r5": (5, 3, _sphere_product([2, 3], [0.0213, -0.0147, -0.0181, 0.0262, 0.0119],
                                       [0.83, 0.61])),
    "flat-3torus-r6": (6, 3, _sphere_product(
        [2, 2, 2], [0.0213, -0.0147, -0.0181, 0.0262, 0.0119, -0.0231], [0.71, 0.67, 0.63])),
    "o3-r9": (9, 3, _orthogonal_group()),
}

# --- Topology ----------------------------------------------------------------------------------


def _faces(simplices):
    """The distinct facets of the simplices (sorted rows) and, per simplex, its facets' rows."""
    k = simplices.shape[1]
    facets = np.sort(np.concatenate([np.delete(simplices, i, axis=1) for i in range(k)]), axis=1)
    unique, inverse = np.unique(facets, axis=0, return_inverse=True)
    return unique, inverse.reshape(-1).reshape(k, -1).T


def betti3(nv, tets, limit=1000000):
    """Betti numbers over Z/2 and over Q of a closed 3-dimensional pseudomanifold (every
    triangle in exactly two tetrahedra), or None for any other mesh or one whose reduced complex
    keeps more than `limit` cells.

    One vertex per component and one tetrahedron per strongly connected component (tetrahedra
    joined through triangles) are removed; then coreductions (a cell with one live face goes with
    it) and collapses (a cell with one live coface goes with it) run until none is left. Both
    only delete entries of the boundary matrices, so the live cells' restricted boundaries are a
    complex with the same homology, whose ranks are then computed. The removed vertex lowers b0
    by one; the removed tetrahedron lowers b3 by one over Z/2 (the sum of all the component's
    tetrahedra is a cycle) and over Q where the component is orientable, and raises b2 by one
    over Q where it is not."""
    tets = np.sort(tets, axis=1)  # facet i (without vertex i) then has the sign (-1)^i
    triangles, tet_tris = _faces(tets)
    counts = np.bincount(tet_tris.ravel(), minlength=len(triangles))
    if len(tets) == 0 or (counts != 2).any():
        return None
    edges, tri_edges = _faces(triangles)
    # Strongly connected components and their orientability: the two tetrahedra of a triangle
    # are consistently oriented when its signs in their boundaries are opposite.
    pair = np.argsort(tet_tris.ravel(), kind="stable").reshape(-1, 2).tolist()
    neighbours = [[] for _ in range(len(tets))]
    for a, b in pair:
        neighbours[a // 4].append((b // 4, a % 4, b % 4))
        neighbours[b // 4].append((a // 4, b % 4, a % 4))
    orient = [0] * len(tets)
    starts, orientable = [], 0
    for start in range(len(tets)):
        if orient[start]:
            continue
        starts.append(start)
        ok = True
        orient[start] = 1
        stack = [start]
        while stack:
            t = stack.pop()
            for u, i, j in neighbours[t]:
                want = -orient[t] * (-1) ** (i + j)
                if not orient[u]:
                    orient[u] = want
                    stack.append(u)
                elif orient[u] != want:
                    ok = False
        orientable += ok
    # The complex: faces[d][c] lists the faces of cell c of dimension d (d = 1, 2, 3), in the
    # order of their signs (-1)^i; cofaces[d][c] the cofaces of cell c of dimension d.
    faces = [None, edges.tolist(), tri_edges.tolist(), tet_tris.tolist()]
    sizes = [nv, len(edges), len(triangles), len(tets)]
    cofaces = [[[] for _ in range(sizes[d])] for d in range(3)] + [None]
    for d in (1, 2, 3):
        for c, fs in enumerate(faces[d]):
            for f in fs:
                cofaces[d - 1][f].append(c)
    alive = [np.ones(sizes[d], bool) for d in range(4)]
    alive[0][:] = False
    alive[0][np.unique(tets)] = True
    live_faces = [None] + [[len(fs) for fs in faces[d]] for d in (1, 2, 3)]
    live_cofaces = [[len(cs) for cs in cofaces[d]] for d in range(3)] + [None]
    queue = []

    def kill(d, c):
        alive[d][c] = False
        if d > 0:
            for f in faces[d][c]:
                if alive[d - 1][f]:
                    live_cofaces[d - 1][f] -= 1
                    queue.append((d - 1, f))
        if d < 3:
            for g in cofaces[d][c]:
                if alive[d + 1][g]:
                    live_faces[d + 1][g] -= 1
                    queue.append((d + 1, g))

    seen = np.zeros(nv, bool)
    components = 0
    for v0 in np.nonzero(alive[0])[0].tolist():
        if seen[v0]:
            continue
        components += 1
        seen[v0] = True
        stack = [v0]
        while stack:
            u = stack.pop()
            for e in cofaces[0][u]:
                for w in faces[1][e]:
                    if not seen[w]:
                        seen[w] = True
                        stack.append(w)
        kill(0, v0)
    for t in starts:
        kill(3, t)
    # First the tetrahedra, each through the triangle it was reached by (a depth-first spanning
    # tree of the dual graph), then coreductions and collapses in any dimension.
    while queue:
        d, c = queue.pop()
        if d == 2 and alive[2][c] and live_cofaces[2][c] == 1:
            g = next(x for x in cofaces[2][c] if alive[3][x])
            kill(2, c)
            kill(3, g)
    queue += [(d, c) for d in range(4) for c in np.nonzero(alive[d])[0].tolist()]
    while queue:
        d, c = queue.pop()
        if not alive[d][c]:
            continue
        if d > 0 and live_faces[d][c] == 1:  # coreduction
            f = next(x for x in faces[d][c] if alive[d - 1][x])
            kill(d, c)
            kill(d - 1, f)
        elif d < 3 and live_cofaces[d][c] == 1:  # collapse
            g = next(x for x in cofaces[d][c] if alive[d + 1][x])
            kill(d, c)
            kill(d + 1, g)
    left = [int(a.sum()) for a in alive]
    if sum(left) > limit:
        return None
    out = {}
    for field, modulus in (("betti_z2", 2), ("betti", 2147483647)):
        b = _reduce(faces, alive, modulus)
        b[0] += components
        if modulus == 2:
            b[3] += len(starts)
        else:
            b[3] += orientable
            b[2] -= len(starts) - orientable  # a non-orientable component's removed tetrahedron
        out[field] = b
    return out


def _reduce(faces, alive, modulus):
    """The Betti numbers over Z/modulus of the complex of the live cells, their boundaries
    restricted to live faces with signs (-1)^i (an edge (a < b) is b - a): pairs (c, f) with f
    in the boundary of c are eliminated, the other cofaces x of f taking
    bd x - (<bd x, f> / <bd c, f>) bd c, until no live cell has a boundary; the cells left are
    the homology."""
    bd = [dict() for _ in range(4)]
    cob = [dict() for _ in range(4)]
    for d in (1, 2, 3):
        for c in np.nonzero(alive[d])[0].tolist():
            row = {f: (-1) ** (i + (d == 1)) % modulus for i, f in enumerate(faces[d][c])
                   if alive[d - 1][f]}
            bd[d][c] = row
            for f in row:
                cob[d - 1].setdefault(f, set()).add(c)
    left = [int(a.sum()) for a in alive]
    for d in (3, 2, 1):
        for c in list(bd[d]):
            row = bd[d].get(c)
            if not row:
                continue
            f = min(row, key=lambda x: len(cob[d - 1][x]))
            inv = pow(row[f], modulus - 2, modulus) if modulus > 2 else 1
            for x in list(cob[d - 1][f]):
                if x == c:
                    continue
                other = bd[d][x]
                factor = other[f] * inv % modulus
                for g, v in row.items():
                    w = (other.get(g, 0) - factor * v) % modulus
                    if w:
                        if g not in other:
                            cob[d - 1][g].add(x)
                        other[g] = w
                    elif g in other:
                        del other[g]
                        cob[d - 1][g].discard(x)
            # Remove c and f: c leaves its faces' cofaces and its cofaces' boundaries, f its
            # faces' cofaces.
            for g in row:
                cob[d - 1][g].discard(c)
            del bd[d][c]
            for y in cob[d].pop(c, ()):
                bd[d + 1][y].pop(c, None)
            if d - 1 > 0:
                for g in bd[d - 1].pop(f, {}):
                    cob[d - 2][g].discard(f)
            cob[d - 1].pop(f, None)
            left[d] -= 1
            left[d - 1] -= 1
    return left


def _components(nv, pairs):
    """The connected components of nv vertices joined by the (a, b) pairs (union-find)."""
    parent = np.arange(nv)

    def find(a):
        root = a
        while parent[root] != root:
            root = parent[root]
        while parent[a] != root:
            parent[a], a = root, parent[a]
        return root

    for a, b in pairs:
        ra, rb = find(a), find(b)
        if ra != rb:
            parent[ra] = rb
    return len({find(v) for v in range(nv)})


def topology(nv, simplices):
    if simplices.shape[1] == 4:
        return topology3(nv, simplices)

    if simplices.shape[1] == 3:
        edges = np.sort(np.concatenate([simplices[:, [0, 1]], simplices[:, [1, 2]],
                                        simplices[:, [0, 2]]]), axis=1)
        unique, counts = np.unique(edges, axis=0, return_counts=True)
    else:
        unique = np.unique(np.sort(simplices, axis=1), axis=0)
        counts = None
    used = np.zeros(nv, bool)
    used[simplices.ravel()] = True
    t = {"vertices": int(nv), "simplices": int(len(simplices)),
         "components": _components(nv, unique.tolist()),
         "unused_vertices": int((~used).sum())}
    if simplices.shape[1] == 3:
        t["euler"] = int(nv - len(unique) + len(simplices))
        t["boundary_edges"] = int((counts == 1).sum())
        t["nonmanifold_edges"] = int((counts > 2).sum())
    else:
        t["euler"] = int(nv - len(unique))
        degree = np.bincount(unique.ravel(), minlength=nv)
        t["bad_vertices"] = int((degree != 2).sum())
    return t


def topology3(nv, tets):
    """Vertices, tetrahedra, components, Euler characteristic, boundary and non-manifold
    triangles and (closed meshes) the Betti numbers of a tetrahedral mesh."""
    triangles, tet_tris = _faces(tets)
    edges, _ = _faces(triangles)
    counts = np.bincount(tet_tris.ravel(), minlength=len(triangles))

    used = np.zeros(nv, bool)
    used[tets.ravel()] = True
    t = {"vertices": int(nv), "simplices": int(len(tets)),
         "components": _components(nv, edges.tolist()), "unused_vertices": int((~used).sum()),
         "euler": int(nv - len(edges) + len(triangles) - len(tets)),
         "boundary_triangles": int((counts == 1).sum()),
         "nonmanifold_triangles": int((counts > 2).sum())}
    b = betti3(nv, tets)
    if b:
        t.update(b)
    return t


# --- Distances ---------------------------------------------------------------------------------


def _seg_d2(p, a, b):
    e = b - a
    ee = np.maximum((e * e).sum(axis=1), 1e-300)
    t = np.clip(((p - a) * e).sum(axis=1) / ee, 0, 1)
    w = p - a - t[:, None] * e
    return (w * w).sum(axis=1)


def _tri_d2(p, a, b, c):
    e0, e1, w = b - a, c - a, p - a
    g00, g01, g11 = (e0 * e0).sum(1), (e0 * e1).sum(1), (e1 * e1).sum(1)
    r0, r1 = (w * e0).sum(1), (w * e1).sum(1)
    det = g00 * g11 - g01 * g01
    ok = det > 1e-14 * np.maximum(g00 * g11, 1e-300)
    sdet = np.where(ok, det, 1.0)
    s = (g11 * r0 - g01 * r1) / sdet
    t = (g00 * r1 - g01 * r0) / sdet
    inside = ok & (s >= 0) & (t >= 0) & (s + t <= 1)
    q = w - s[:, None] * e0 - t[:, None] * e1
    d2 = np.where(inside, (q * q).sum(1), np.inf)
    return np.minimum(d2, np.minimum(_seg_d2(p, a, b),
                                     np.minimum(_seg_d2(p, a, c), _seg_d2(p, b, c))))


def mesh_points(points, simplices):
    """The vertices and a barycentric grid on every simplex, in pieces (one per grid point of
    the simplex: a tetrahedral mesh's grid does not fit in memory at once)."""
    if simplices.shape[1] == 4:
        m = 3
        bary = [(i / m, j / m, l / m, 1 - (i + j + l) / m) for i in range(m + 1)
                for j in range(m + 1 - i) for l in range(m + 1 - i - j) if 0 < i + j + l]
    elif simplices.shape[1] == 3:
        m = 4
        bary = [(i / m, j / m, 1 - (i + j) / m) for i in range(m + 1) for j in range(m + 1 - i)
                if 0 < i + j]
    else:
        m = 8
        bary = [(i / m, 1 - i / m) for i in range(1, m)]
    yield points
    for w in bary:
        yield sum(wi * points[simplices[:, i]] for i, wi in enumerate(w))


def _tet_d2(p, a, b, c, d):
    """Squared distance of points p to tetrahedra (a, b, c, d) in R^n: the foot in the affine
    hull where it lies inside, otherwise the nearest of the four faces."""
    e = np.stack([b - a, c - a, d - a], axis=1)  # (N, 3, n)
    w = p - a
    gram = e @ e.transpose(0, 2, 1)
    rhs = (e @ w[:, :, None])[:, :, 0]
    det = np.linalg.det(gram)
    ok = det > 1e-12 * np.maximum(np.prod(np.diagonal(gram, axis1=1, axis2=2), axis=1), 1e-300)
    lam = np.zeros_like(rhs)
    lam[ok] = np.linalg.solve(gram[ok], rhs[ok][:, :, None])[:, :, 0]
    inside = ok & (lam >= 0).all(axis=1) & (lam.sum(axis=1) <= 1)
    q = w - (lam[:, :, None] * e).sum(axis=1)
    d2 = np.where(inside, (q * q).sum(axis=1), np.inf)
    for f in ((a, b, c), (a, b, d), (a, c, d), (b, c, d)):
        d2 = np.minimum(d2, _tri_d2(p, *f))
    return d2


def distance_to_tets(samples, points, tets, nearest=4, chunk=5000):
    """Distance of each sample to the tetrahedra around its `nearest` nearest mesh vertices
    (an upper bound of the distance to the mesh; exact unless the nearest tetrahedron has none
    of those vertices)."""
    from scipy.spatial import cKDTree
    owner = np.repeat(np.arange(len(tets)), 4)
    verts = tets.ravel()
    order = np.argsort(verts, kind="stable")
    vs, owner = verts[order], owner[order]
    ptr = np.searchsorted(vs, np.arange(len(points) + 1))
    tree = cKDTree(points)
    out = np.empty(len(samples))
    for start in range(0, len(samples), chunk):
        s = samples[start:start + chunk]
        _, vi = tree.query(s, k=nearest)
        si = np.repeat(np.arange(len(s)), nearest)
        vi = vi.ravel()
        counts = ptr[vi + 1] - ptr[vi]
        srep = np.repeat(si, counts)
        offs = np.repeat(ptr[vi] - np.cumsum(counts) + counts, counts) + np.arange(counts.sum())
        key = np.unique(srep * len(tets) + owner[offs])
        srep, sim = key // len(tets), key % len(tets)
        t = tets[sim]
        dd = _tet_d2(s[srep], points[t[:, 0]], points[t[:, 1]], points[t[:, 2]],
                     points[t[:, 3]])
        best = np.full(len(s), np.inf)
        np.minimum.at(best, srep, dd)
        out[start:start + chunk] = np.sqrt(best)
    return out


def max_distance_to_tets(samples, points, tets, chunk=2000):
    """The largest distance of the samples to the tetrahedra: first over the tetrahedra around
    each sample's 4 nearest vertices, then, from the farthest samples down, over those around
    its 32 nearest, until no sample left can exceed the refined maximum (each first value is an
    upper bound of the second)."""
    rough = distance_to_tets(samples, points, tets, nearest=4)
    order = np.argsort(-rough)
    best = 0.0
    for start in range(0, len(order), chunk):
        if best >= rough[order[start]]:
            break
        part = order[start:start + chunk]
        best = max(best, float(distance_to_tets(samples[part], points, tets, nearest=32).max()))
    return best


def distance_to_mesh(samples, points, simplices, chunk=96):
    """Exact distance of each sample to the union of the simplices."""
    nv = len(points)
    k = simplices.shape[1]
    # Vertex -> simplices (CSR), and the largest simplex diameter D: the simplex nearest to p has
    # a vertex within d(p, nearest vertex) + D of p.
    owner = np.repeat(np.arange(len(simplices)), k)
    verts = simplices.ravel()
    order = np.argsort(verts, kind="stable")
    vs, owner = verts[order], owner[order]
    ptr = np.searchsorted(vs, np.arange(nv + 1))
    diam = 0.0
    for i in range(k):
        for j in range(i + 1, k):
            diam = max(diam, float(np.linalg.norm(points[simplices[:, i]] -
                                                  points[simplices[:, j]], axis=1).max()))
    try:
        from scipy.spatial import cKDTree
    except ImportError:
        cKDTree = None
    pn = (points * points).sum(1)
    tree = cKDTree(points) if cKDTree is not None else None
    out = np.empty(len(samples))
    chunk = 20000 if tree is not None else chunk
    for start in range(0, len(samples), chunk):
        s = samples[start:start + chunk]
        if tree is not None:
            dv, _ = tree.query(s, k=1)
            thr = (dv + diam) * (1 + 1e-9) + 1e-12
            near = tree.query_ball_point(s, thr)
            counts = np.fromiter((len(x) for x in near), dtype=np.int64, count=len(s))
            si = np.repeat(np.arange(len(s)), counts)
            vi = np.fromiter((v for x in near for v in x), dtype=np.int64, count=int(counts.sum()))
        else:
            d2 = np.maximum((s * s).sum(1)[:, None] + pn[None, :] - 2 * s @ points.T, 0)
            dv = np.sqrt(d2.min(axis=1))
            thr = (dv + diam) * (1 + 1e-9) + 1e-12
            si, vi = np.nonzero(d2 <= (thr * thr)[:, None])
        counts = ptr[vi + 1] - ptr[vi]
        srep = np.repeat(si, counts)
        offs = np.repeat(ptr[vi] - np.cumsum(counts) + counts, counts) + np.arange(counts.sum())
        sim = owner[offs]
        key = np.unique(srep * len(simplices) + sim)
        srep, sim = key // len(simplices), key % len(simplices)
        p = s[srep]
        if k == 3:
            dd = _tri_d2(p, points[simplices[sim, 0]], points[simplices[sim, 1]],
                         points[simplices[sim, 2]])
        else:
            dd = _seg_d2(p, points[simplices[sim, 0]], points[simplices[sim, 1]])
        best = np.full(len(s), np.inf)
        np.minimum.at(best, srep, dd)
        out[start:start + chunk] = np.sqrt(best)
    return out


# The sample spacing on M of the 3-manifolds (their samples grow as spacing^-3).
SPACING3 = {"o3-r9": 0.2}


def measure(problem, path, spacing=0.02):
    n, k, exact = PROBLEMS[problem]
    points, simplices = read_mesh(path, n, k)
    result = {"problem": problem, "mesh": path}
    result.update(topology(len(points), simplices))
    if len(simplices) == 0:
        result["error"] = math.inf
        return result
    if exact is None:
        result["residual"] = max(float(_genus2_residual(x).max())
                                 for x in mesh_points(points, simplices))
        result["error"] = result["residual"]
        result["error_kind"] = "max |F|/|grad F|"
        return result
    dist, samples = exact
    to_m = max(float(dist(x).max()) for x in mesh_points(points, simplices))
    if k == 3:
        sample = samples(max(spacing, SPACING3.get(problem, 0.08)))
        to_mesh = max_distance_to_tets(sample, points, simplices)
    else:
        sample = samples(spacing)
        to_mesh = float(distance_to_mesh(sample, points, simplices).max())
    result.update({"mesh_to_M": to_m, "M_to_mesh": to_mesh, "samples": len(sample),
                   "error": max(to_m, to_mesh), "error_kind": "Hausdorff"})
    return result


def main(argv):
    if len(argv) < 3 or argv[1] not in PROBLEMS:
        sys.stderr.write(__doc__)
        return 2
    spacing = 0.02
    if "--spacing" in argv:
        spacing = float(argv[argv.index("--spacing") + 1])
    print(json.dumps(measure(argv[1], argv[2], spacing)))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
