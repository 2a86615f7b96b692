#!/usr/bin/python3
"""Independent error and topology of a mesh of a peer-benchmark problem (bench/, docs/performance.md).

Usage: bench/measure.py PROBLEM MESH.ply [--spacing H]   (sample spacing on M, default 0.02)

Reads an ASCII or binary_little_endian PLY (ndcontour's mesh.ply, or the output of
bench/cgal_torus and bench/gudhi_trace: coordinates u0..u{n-1}, or x y z when there are no u's;
faces or edges), and prints one JSON line with

* the topology: vertices, simplices, components, Euler characteristic, boundary and
  non-manifold edges (surfaces) or vertices of degree other than 2 (curves);
* for the problems whose distance function is known in closed form (torus,
  clifford-torus-rotated, sphere-r5, flat-torus-r6, circle-r8): the two-sided Hausdorff distance
  between the mesh and the true manifold M. Mesh -> M: the exact distance to M of the vertices and
  of a barycentric grid on every simplex (4 steps per triangle edge, 8 per segment). M -> mesh:
  the exact point-to-triangle (point-to-segment) distance to the mesh of a dense sample of M
  (spacing about 0.02: it finds missing or misplaced pieces of the mesh; the chord error between
  the samples is what the mesh -> M side measures);
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


def read_mesh(path, n):
    """Vertices (V x n) and simplices (S x 2 segments, or S x 3 triangles; polygons fanned)."""
    ply = read_ply(path)
    vert = ply["vertex"]
    names = [f"u{j}" for j in range(n)] if "u0" in vert else ["x", "y", "z"][:n]
    points = np.column_stack([np.asarray(vert[c], dtype=float) for c in names])
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


def _sphere_section(m, d):
    """Unit sphere cut by M x + d = 0: a sphere of radius rho about c0 in the flat."""
    m, d = np.asarray(m, float), np.asarray(d, float)
    gram = m @ m.T
    c0 = -m.T @ np.linalg.solve(gram, d)
    rho = math.sqrt(1 - c0 @ c0)
    _, _, vt = np.linalg.svd(m)
    basis = vt[m.shape[0]:]  # orthonormal basis of the flat's directions
    k = basis.shape[0] - 1   # dimension of the sphere

    def dist(x):
        y = x - c0
        inplane = y @ basis.T
        h2 = (y ** 2).sum(axis=1) - (inplane ** 2).sum(axis=1)
        return np.sqrt(np.maximum(h2, 0) + (np.linalg.norm(inplane, axis=1) - rho) ** 2)

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
}

# --- Topology ----------------------------------------------------------------------------------


def topology(nv, simplices):
    parent = np.arange(nv)

    def find(a):
        root = a
        while parent[root] != root:
            root = parent[root]
        while parent[a] != root:
            parent[a], a = root, parent[a]
        return root

    if simplices.shape[1] == 3:
        edges = np.sort(np.concatenate([simplices[:, [0, 1]], simplices[:, [1, 2]],
                                        simplices[:, [0, 2]]]), axis=1)
        unique, counts = np.unique(edges, axis=0, return_counts=True)
    else:
        unique = np.unique(np.sort(simplices, axis=1), axis=0)
        counts = None
    for a, b in unique.tolist():
        ra, rb = find(a), find(b)
        if ra != rb:
            parent[ra] = rb
    used = np.zeros(nv, bool)
    used[simplices.ravel()] = True
    roots = {find(v) for v in range(nv)}
    t = {"vertices": int(nv), "simplices": int(len(simplices)), "components": len(roots),
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
    """The vertices and a barycentric grid on every simplex."""
    if simplices.shape[1] == 3:
        m = 4
        bary = [(i / m, j / m, 1 - (i + j) / m) for i in range(m + 1) for j in range(m + 1 - i)
                if 0 < i + j]
    else:
        m = 8
        bary = [(i / m, 1 - i / m) for i in range(1, m)]
    out = [points]
    for w in bary:
        out.append(sum(wi * points[simplices[:, i]] for i, wi in enumerate(w)))
    return np.concatenate(out)


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


def measure(problem, path, spacing=0.02):
    n, k, exact = PROBLEMS[problem]
    points, simplices = read_mesh(path, n)
    result = {"problem": problem, "mesh": path}
    result.update(topology(len(points), simplices))
    if len(simplices) == 0:
        result["error"] = math.inf
        return result
    on_mesh = mesh_points(points, simplices)
    if exact is None:
        result["residual"] = float(_genus2_residual(on_mesh).max())
        result["error"] = result["residual"]
        result["error_kind"] = "max |F|/|grad F|"
        return result
    dist, samples = exact
    to_m = float(dist(on_mesh).max())
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
