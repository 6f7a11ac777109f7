"""Shared scene and metrics of the drape peers (benchmarks.md, "Cloth at the size users simulate: drapes").

Scene (anima's `OliveiraScene` drapes, Oliveira 2013 Table 5.5 material):
  * cloth: 1 m square, V x V vertices (V = 65, 129, 257), vertex (row, col) at index row*V + col, material
    coordinates X = (col, row) * h with h = 1/(V-1); every grid square split by the same diagonal, (row, col) to
    (row+1, col+1) (anima's `DiagonalPattern::Uniform`): triangles [p, p+1, p+V+1] and [p, p+V+1, p+V],
    counter-clockwise seen from +z. Flat and horizontal, centre over the obstacle's highest point (x, y of the
    highest vertex) and CLEARANCE = 1 cm above it, at rest.
  * obstacles: `bunny` = assets/meshes/bunny.obj (3,674 triangles, closed, y up in the file) rotated to z up
    (p' = (x, -z, y)), scaled so that its longest horizontal side is 0.5 m, the centre of its bounding box's bottom
    at the origin (anima's `place_mesh`), standing on the floor z = 0; `sphere` = radius 0.25 m centred at
    (0, 0, 0.25) on the same floor.
  * material (anima's Oliveira model, the reference every peer maps from):
      areal density RHO_A = 6000 kg/m^3 * 1e-4 m = 0.6 kg/m^2, lumped: particle mass = 1/3 of the adjacent
      triangles' area * RHO_A;
      every mesh edge a tension-only spring k = E*A0/L0 = 1e7 * 2.5e-6 / L0 N/m, damping 0.01*k N s/m along it;
      air drag C_i = area_i * 3 kg/s per particle (so C_i/m_i = 3/0.6 = 5 1/s everywhere);
      Bridson dihedral bending, stiffness 1e-3, damping 1e-4; friction 0.3, restitution 0;
      gravity -9.81 z; 3 s at 1/60 s.

Equivalent membrane of the spring network (used by the peers whose cloth is a triangle FEM membrane): per grid
square the network has one x edge and one y edge (k = EA0/h) and one diagonal (k = EA0/(h sqrt 2)); its small-strain
energy density is  W = (k~/2) [exx^2 + eyy^2 + (sqrt2/4)(exx + eyy + 2 exy)^2]  with k~ = E A0 / h. That lattice is
anisotropic (one diagonal); its isotropic projection (the orientation average of its stiffness tensor, which keeps
the equi-biaxial stiffness exactly) is
    mu_2D = lambda_2D = (2 + sqrt2)/8 * k~,  i.e.  E*t = (2 + sqrt2)/3 * k~,  nu = 1/3.
Note k~ grows as 1/h: the spring network stiffens with resolution (A0 is a fixed cross-section), so the membrane
stiffness is per V: k~ = 1600, 3200, 6400 N/m for V = 65, 129, 257.
Spring damping 0.01*k along every spring is stiffness-proportional (Rayleigh) damping with beta = 0.01 s.
Bridson's element (anima's bending.rs) is, for small angles, the hinge energy  1/2 k_b |e|^2/(2(|N1|+|N2|)) theta^2
= 1/2 k_b L0/(4 (A1 + A2)) * L0 * theta^2: per unit rest length, k_b L0 / (4 (A1 + A2)) (k_b/(4h) on the grid's
axis edges, k_b/(2 sqrt2 h) on its diagonals); its damping  k_d |e| theta_dot  per hinge. As a plate (measured on
the grid, independent of h) it is anisotropic: stiffness k_b/4 for cylindrical bends curving along either grid axis
or across the split diagonals, 3 k_b/4 for bends curving along them; averaged over directions D = 3 k_b/8 (PLATE_D).
"""
import json, math, os, sys, time
import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.normpath(os.path.join(HERE, "..", ".."))
BUNNY_OBJ = os.path.join(REPO, "assets", "meshes", "bunny.obj")

SIZE = 1.0
CLEARANCE = 0.01
RHO_A = 6000.0 * 1e-4          # kg/m^2
YOUNG = 1e7                    # Pa
A0 = 2.5e-6                    # m^2 spring cross-section
EA = YOUNG * A0                # N
DAMP_RATIO = 0.01              # s (k_d = 0.01 k)
PERMEABILITY = 3.0             # kg/(m^2 s)
DRAG_RATE = PERMEABILITY / RHO_A   # 1/s, C_i/m_i
BEND_K = 1e-3
BEND_D = 1e-4
PLATE_D = 3.0 * BEND_K / 8.0   # N m, orientation-averaged plate bending stiffness of the hinges
FRICTION = 0.3
G = 9.81
DURATION = 3.0
DT = 1.0 / 60.0
BUNNY_LENGTH = 0.5
SPHERE_C = np.array([0.0, 0.0, 0.25])
SPHERE_R = 0.25


# ---------------------------------------------------------------- cloth
def grid_triangles(V):
    """Triangles of the V x V grid, uniform diagonal, CCW from +z (anima's MaterialMesh::grid, Uniform)."""
    r, c = np.meshgrid(np.arange(V - 1), np.arange(V - 1), indexing="ij")
    p = (r * V + c).ravel()
    t1 = np.stack([p, p + 1, p + V + 1], axis=1)
    t2 = np.stack([p, p + V + 1, p + V], axis=1)
    return np.stack([t1, t2], axis=1).reshape(-1, 3).astype(np.int32)


def rest_grid(V):
    """Material coordinates (col*h, row*h) of vertex row*V + col."""
    h = SIZE / (V - 1)
    k = np.arange(V * V)
    return np.stack([(k % V) * h, (k // V) * h], axis=1)


def edges_of(tris):
    """Unique undirected edges (E,2), sorted."""
    e = np.concatenate([tris[:, [0, 1]], tris[:, [1, 2]], tris[:, [2, 0]]])
    e = np.sort(e, axis=1)
    return np.unique(e, axis=0)


def tri_areas(x, tris):
    a, b, c = x[tris[:, 0]], x[tris[:, 1]], x[tris[:, 2]]
    if x.shape[1] == 2:
        return 0.5 * np.abs((b - a)[:, 0] * (c - a)[:, 1] - (b - a)[:, 1] * (c - a)[:, 0])
    return 0.5 * np.linalg.norm(np.cross(b - a, c - a), axis=1)


def vertex_areas(V):
    tris = grid_triangles(V)
    A = tri_areas(rest_grid(V), tris)
    va = np.zeros(V * V)
    for j in range(3):
        np.add.at(va, tris[:, j], A / 3.0)
    return va


def masses(V):
    return RHO_A * vertex_areas(V)


def springs(V):
    """Mesh edges as anima's springs: (idx[E,2], rest[E], k[E] N/m, kd[E] N s/m)."""
    e = edges_of(grid_triangles(V))
    X = rest_grid(V)
    L0 = np.linalg.norm(X[e[:, 0]] - X[e[:, 1]], axis=1)
    k = EA / L0
    return e.astype(np.int32), L0, k, DAMP_RATIO * k


def membrane_equivalent(V):
    """Isotropic membrane of the spring network (see the module docstring): dict of k~, E*t, nu, mu, lambda (N/m)."""
    h = SIZE / (V - 1)
    kt = EA / h
    mu = (2.0 + math.sqrt(2.0)) / 8.0 * kt
    return {"k_tilde": kt, "Et": (2.0 + math.sqrt(2.0)) / 3.0 * kt, "nu": 1.0 / 3.0, "mu": mu, "lam": mu}


def hinge_bending_per_length(x_rest3, hinge):
    """Bridson's small-angle hinge stiffness per unit rest length, k_b L0 / (4 (A1 + A2)), for hinges
    (o0, o1, e0, e1) (two opposite vertices, then the shared edge)."""
    o0, o1, a, b = (x_rest3[hinge[:, j]] for j in range(4))
    L0 = np.linalg.norm(b - a, axis=1)
    A1 = 0.5 * np.linalg.norm(np.cross(a - o0, b - o0), axis=1)
    A2 = 0.5 * np.linalg.norm(np.cross(a - o1, b - o1), axis=1)
    return BEND_K * L0 / (4.0 * (A1 + A2))


# ---------------------------------------------------------------- obstacles
def read_obj(path):
    vs, fs = [], []
    with open(path) as f:
        for line in f:
            s = line.split()
            if not s:
                continue
            if s[0] == "v":
                vs.append([float(t) for t in s[1:4]])
            elif s[0] == "f":
                ids = [int(t.split("/")[0]) for t in s[1:]]
                ids = [i - 1 if i > 0 else len(vs) + i for i in ids]
                for j in range(1, len(ids) - 1):  # fan-triangulate polygons
                    fs.append([ids[0], ids[j], ids[j + 1]])
    return np.array(vs, dtype=np.float64), np.array(fs, dtype=np.int32)


def bunny(path=BUNNY_OBJ, length=BUNNY_LENGTH, base_centre=(0.0, 0.0, 0.0)):
    """The Bunny placed as anima's `place_mesh(mesh, Y, length, base_centre)`: (vertices[n,3], triangles[m,3])."""
    v, f = read_obj(path)
    r = np.stack([v[:, 0], -v[:, 2], v[:, 1]], axis=1)  # y up -> z up
    lo, hi = r.min(0), r.max(0)
    scale = length / max(hi[0] - lo[0], hi[1] - lo[1])
    bottom = np.array([(lo[0] + hi[0]) / 2, (lo[1] + hi[1]) / 2, lo[2]])
    return np.asarray(base_centre) + (r - bottom) * scale, f


def highest_point(obstacle, bunny_mesh=None):
    if obstacle == "bunny":
        v = bunny_mesh[0] if bunny_mesh is not None else bunny()[0]
        return v[np.argmax(v[:, 2])]
    return SPHERE_C + np.array([0.0, 0.0, SPHERE_R])


def cloth_positions(V, obstacle, bunny_mesh=None, clearance=CLEARANCE):
    """Initial positions (V*V, 3): centre over the highest point, `clearance` above it."""
    top = highest_point(obstacle, bunny_mesh)
    X = rest_grid(V)
    origin = top[:2] - SIZE / 2.0
    x = np.empty((V * V, 3))
    x[:, :2] = origin + X
    x[:, 2] = top[2] + clearance
    return x


def cloth_setup(V, obstacle):
    """What every peer builds first, in this order: the grid spacing h, the Bunny mesh (None over the
    sphere), the cloth's initial positions, its triangles and its membrane equivalent."""
    h = SIZE / (V - 1)
    bm = bunny() if obstacle == "bunny" else None
    return h, bm, cloth_positions(V, obstacle, bm), grid_triangles(V), membrane_equivalent(V)


# ---------------------------------------------------------------- metrics
def winding_numbers(p, verts, tris, chunk=2048):
    """Generalized winding number of points p[n,3] w.r.t. a closed triangle mesh (van Oosterom-Strackee)."""
    out = np.zeros(len(p))
    A, B, C = verts[tris[:, 0]], verts[tris[:, 1]], verts[tris[:, 2]]
    for s in range(0, len(p), chunk):
        q = p[s:s + chunk, None, :]
        a, b, c = A[None] - q, B[None] - q, C[None] - q
        la, lb, lc = (np.linalg.norm(v, axis=2) for v in (a, b, c))
        det = np.einsum("ijk,ijk->ij", a, np.cross(b, c))
        den = (la * lb * lc + np.einsum("ijk,ijk->ij", a, b) * lc + np.einsum("ijk,ijk->ij", b, c) * la
               + np.einsum("ijk,ijk->ij", c, a) * lb)
        out[s:s + chunk] = np.arctan2(det, den).sum(axis=1) / (2.0 * np.pi)
    return out


class MeshInside:
    """Inside test for a closed triangle mesh: parity of the crossings of a ray straight up (+z), with the
    triangles binned by their xy bounding boxes; points whose ray passes within 1e-9 (barycentric) of an edge
    or vertex are settled by the generalized winding number instead."""

    def __init__(self, verts, tris, cell=None):
        self.v, self.t = np.asarray(verts, np.float64), np.asarray(tris, np.int64)
        self.lo, self.hi = self.v.min(0), self.v.max(0)
        P = self.v[self.t]                                # (m,3,3)
        tlo, thi = P[:, :, :2].min(1), P[:, :, :2].max(1)
        ext = self.hi[:2] - self.lo[:2]
        self.cell = cell or float(np.sqrt(ext[0] * ext[1] / max(len(self.t), 1)) * 2.0)
        self.nb = np.maximum(np.ceil(ext / self.cell).astype(int), 1)
        i0 = np.clip(((tlo - self.lo[:2]) / self.cell).astype(int), 0, self.nb - 1)
        i1 = np.clip(((thi - self.lo[:2]) / self.cell).astype(int), 0, self.nb - 1)
        bins, tri = [], []
        for t in range(len(self.t)):
            bx, by = np.meshgrid(np.arange(i0[t, 0], i1[t, 0] + 1), np.arange(i0[t, 1], i1[t, 1] + 1), indexing="ij")
            b = (bx * self.nb[1] + by).ravel()
            bins.append(b); tri.append(np.full(len(b), t))
        bins, tri = np.concatenate(bins), np.concatenate(tri)
        order = np.argsort(bins, kind="stable")
        self.bin_tris = tri[order]
        self.bin_start = np.searchsorted(bins[order], np.arange(self.nb[0] * self.nb[1] + 1))
        self.P = P

    def contains(self, x):
        x = np.asarray(x, np.float64)
        res = np.zeros(len(x), dtype=bool)
        cand = np.nonzero(np.all((x > self.lo) & (x < self.hi), axis=1))[0]
        if not len(cand):
            return res
        q = x[cand]
        ij = np.clip(((q[:, :2] - self.lo[:2]) / self.cell).astype(int), 0, self.nb - 1)
        b = ij[:, 0] * self.nb[1] + ij[:, 1]
        s, e = self.bin_start[b], self.bin_start[b + 1]
        cnt = e - s
        pt = np.repeat(np.arange(len(q)), cnt)
        off = np.arange(cnt.sum()) - np.repeat(np.cumsum(cnt) - cnt, cnt)
        tr = self.bin_tris[np.repeat(s, cnt) + off]
        A, B, C = self.P[tr, 0], self.P[tr, 1], self.P[tr, 2]
        p = q[pt]
        # barycentric coordinates of p's xy in the projected triangle
        d = (B[:, 0] - A[:, 0]) * (C[:, 1] - A[:, 1]) - (B[:, 1] - A[:, 1]) * (C[:, 0] - A[:, 0])
        ok = np.abs(d) > 0
        d = np.where(ok, d, 1.0)
        l1 = ((p[:, 0] - A[:, 0]) * (C[:, 1] - A[:, 1]) - (p[:, 1] - A[:, 1]) * (C[:, 0] - A[:, 0])) / d
        l2 = ((B[:, 0] - A[:, 0]) * (p[:, 1] - A[:, 1]) - (B[:, 1] - A[:, 1]) * (p[:, 0] - A[:, 0])) / d
        l0 = 1.0 - l1 - l2
        inside_xy = ok & (l0 > 0) & (l1 > 0) & (l2 > 0)
        z = l0 * A[:, 2] + l1 * B[:, 2] + l2 * C[:, 2]
        hit = inside_xy & (z > p[:, 2])
        crossings = np.bincount(pt[hit], minlength=len(q))
        res[cand] = crossings % 2 == 1
        eps = 1e-9
        near = ok & (np.minimum(np.minimum(np.abs(l0), np.abs(l1)), np.abs(l2)) < eps) & (z > p[:, 2] - eps)
        amb = np.unique(pt[near])
        if len(amb):
            res[cand[amb]] = winding_numbers(q[amb], self.v, self.t) > 0.5
        return res


_inside_cache = {}


def inside_counts(x, obstacle, bunny_mesh=None):
    """Particles strictly inside each obstacle: {"floor": z < 0, "sphere"/"bunny": ..., "total": union}."""
    x = np.asarray(x, dtype=np.float64)
    floor = x[:, 2] < 0.0
    if obstacle == "sphere":
        obj = np.linalg.norm(x - SPHERE_C, axis=1) < SPHERE_R
    else:
        verts, tris = bunny_mesh if bunny_mesh is not None else bunny()
        key = (id(verts), len(verts))
        if key not in _inside_cache:
            _inside_cache.clear()
            _inside_cache[key] = MeshInside(verts, tris)
        obj = _inside_cache[key].contains(x)
    return {"floor": int(floor.sum()), obstacle: int(obj.sum()), "total": int((floor | obj).sum())}


def _cells(lo, hi, cell, origin):
    """For boxes [lo, hi] (n,3): (cell key, box id) for every grid cell each box touches."""
    i0 = np.floor((lo - origin) / cell).astype(np.int64)
    i1 = np.floor((hi - origin) / cell).astype(np.int64)
    ext = i1 - i0 + 1
    cnt = ext.prod(axis=1)
    box = np.repeat(np.arange(len(lo)), cnt)
    k = np.arange(cnt.sum()) - np.repeat(np.cumsum(cnt) - cnt, cnt)
    e = ext[box]
    ix = i0[box, 0] + k % e[:, 0]
    iy = i0[box, 1] + (k // e[:, 0]) % e[:, 1]
    iz = i0[box, 2] + k // (e[:, 0] * e[:, 1])
    key = (ix * 2097152 + iy) * 2097152 + iz
    return key, box


def crossing_pairs(x, V):
    """Edge-triangle pairs of the cloth that cross (an edge passing through a triangle it does not share a vertex
    with): the self-intersection count of benchmarks.md. Uniform-grid broad phase, exact orientation tests."""
    x = np.asarray(x, dtype=np.float64)
    tris = grid_triangles(V).astype(np.int64)
    edges = edges_of(tris).astype(np.int64)
    cell = 1.0 / (V - 1)
    origin = x.min(axis=0)
    T = x[tris]
    tk, tb = _cells(T.min(axis=1), T.max(axis=1), cell, origin)
    E = x[edges]
    ek, eb = _cells(E.min(axis=1), E.max(axis=1), cell, origin)
    o = np.argsort(tk, kind="stable")
    tk, tb = tk[o], tb[o]
    s = np.searchsorted(tk, ek, "left")
    e = np.searchsorted(tk, ek, "right")
    cnt = e - s
    pe = np.repeat(eb, cnt)
    off = np.arange(cnt.sum()) - np.repeat(np.cumsum(cnt) - cnt, cnt)
    pt = tb[np.repeat(s, cnt) + off]
    pair = np.unique(pe * len(tris) + pt)
    pe, pt = pair // len(tris), pair % len(tris)
    ev, tv = edges[pe], tris[pt]
    shared = (ev[:, :1] == tv).any(axis=1) | (ev[:, 1:] == tv).any(axis=1)
    pe, pt = pe[~shared], pt[~shared]
    p, q = x[edges[pe, 0]], x[edges[pe, 1]]
    a, b, c = x[tris[pt, 0]], x[tris[pt, 1]], x[tris[pt, 2]]

    def vol(u, v, w, z):
        return np.einsum("ij,ij->i", v - u, np.cross(w - u, z - u))

    sp, sq = vol(a, b, c, p), vol(a, b, c, q)
    s1, s2, s3 = vol(p, q, a, b), vol(p, q, b, c), vol(p, q, c, a)
    hit = (sp * sq < 0) & (((s1 > 0) & (s2 > 0) & (s3 > 0)) | ((s1 < 0) & (s2 < 0) & (s3 < 0)))
    return int(hit.sum())


def strain(x, V):
    e, L0, _, _ = springs(V)
    L = np.linalg.norm(x[e[:, 0]] - x[e[:, 1]], axis=1)
    s = L / L0 - 1.0
    return float(s.max()), float(np.abs(s).mean())


def state_metrics(x, v, V, obstacle, bunny_mesh=None, speed_bound=10.0, coord_bound=5.0):
    x = np.asarray(x, dtype=np.float64)
    v = np.asarray(v, dtype=np.float64)
    finite = bool(np.all(np.isfinite(x)) and np.all(np.isfinite(v)))
    out = {"finite": finite}
    if not finite:
        out["stable"] = False
        return out
    speed = np.linalg.norm(v, axis=1)
    smax, smean = strain(x, V)
    out.update({
        "max_speed": float(speed.max()),
        "inside": inside_counts(x, obstacle, bunny_mesh),
        "crossing_pairs": crossing_pairs(x, V),
        "com": x.mean(axis=0).tolist(),
        "max_strain": smax, "mean_abs_strain": smean,
        "max_abs_coord": float(np.abs(x).max()),
    })
    out["stable"] = bool(out["max_speed"] < speed_bound and out["max_abs_coord"] < coord_bound)
    return out


# ---------------------------------------------------------------- command line and results
def add_common_args(ap):
    ap.add_argument("V", type=int, help="vertices per side (65, 129, 257)")
    ap.add_argument("dt", type=float, nargs="?", default=DT, help="step, s (default 1/60)")
    ap.add_argument("--obstacle", choices=["bunny", "sphere"], default="bunny")
    ap.add_argument("--duration", type=float, default=DURATION, help="simulated time, s (default 3)")
    ap.add_argument("--gravity-scale", type=float, default=1.0, help="gravity x G (e.g. 1 +- 1e-9 for the band)")
    ap.add_argument("--save", metavar="PATH", help="save the final positions (V*V, 3) as .npy, in grid order")
    ap.add_argument("--chunk", type=int, default=10,
                    help="steps between (untimed) looks at the state, which track the run's largest speed")
    return ap


def n_steps(duration, dt):
    return int(round(duration / dt))


def save_positions(path, x):
    if path:
        d = os.path.dirname(os.path.abspath(path))
        os.makedirs(d, exist_ok=True)
        np.save(path, np.asarray(x, dtype=np.float64))


def emit(rec):
    """Print one `RESULT {json}` line; also append it to the file named by PEERS_OUT, if set."""
    rec.setdefault("host_threads", os.cpu_count())
    try:  # other work on the machine skews wall times: record the load it saw
        rec.setdefault("loadavg_1_5min", [round(v, 2) for v in os.getloadavg()[:2]])
    except OSError:
        pass
    line = json.dumps(rec)
    print("RESULT " + line, flush=True)
    out = os.environ.get("PEERS_OUT")
    if out:
        os.makedirs(os.path.dirname(os.path.abspath(out)), exist_ok=True)
        with open(out, "a") as f:
            f.write(line + "\n")


def drape_record(engine, variant, a, steps, wall, x, v, max_speed_run, bunny_mesh=None, extra=None):
    rec = {"bench": "drape", "engine": engine, "variant": variant, "obstacle": a.obstacle, "V": a.V,
           "dt": a.dt, "steps": steps, "sim_time": steps * a.dt, "gravity_scale": a.gravity_scale,
           "wall_s": wall, "ms_per_step": 1e3 * wall / steps if steps else None,
           "realtime_factor": steps * a.dt / wall if wall > 0 else None,
           "max_speed_run": max_speed_run}
    rec.update(state_metrics(x, v, a.V, a.obstacle, bunny_mesh))
    if max_speed_run is not None and not (math.isfinite(max_speed_run) and max_speed_run < 10.0):
        rec["stable"] = False
    if extra:
        rec.update(extra)
    return rec
