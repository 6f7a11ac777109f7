"""The drapes of benchmarks.md in Newton 1.8 (SolverVBD: implicit Euler by Vertex Block Descent) on Warp's CPU device.

usage: drape_newton.py V [DT] --obstacle bunny|sphere [--iters K] [--duration S] [--save final.npy]
                       [--gravity-scale G] [--membrane fem|springs] [--no-self-contact] ...

Scene: drape_common.py (anima's cloth, Bunny/sphere, floor). The Bunny is a static triangle-mesh shape
(`add_shape_mesh`, body -1: Newton queries the mesh itself, not a hull), the sphere a static sphere shape, the floor
`add_ground_plane`. The cloth is `add_cloth_mesh` over anima's grid with density 0.6 kg/m^2 (Newton lumps one third of
each triangle's area to its corners, as anima does).

Material mapping (anima's Oliveira model -> VBD), every number overridable by a flag:
  membrane, --membrane fem (default): VBD's stable Neo-Hookean membrane with Lame parameters (per unit area, N/m)
      tri_ke = mu, tri_ka = lambda of the spring network's isotropic equivalent (drape_common.py):
      mu = lambda = (2 + sqrt2)/8 * E A0 / h  (E t = (2+sqrt2)/3 * E A0/h, nu = 1/3): 683, 1366, 2731 N/m for
      V = 65, 129, 257. It resists compression, the springs do not.
      tri_kd: VBD damps the rate of the metric C = F^T F with  D = 1/2 kd A |C_dot|^2 = 2 kd A |eps_dot|^2;
      Rayleigh beta = 0.01 s on the shear part 2 mu |eps_dot|^2 * beta/2 gives tri_kd = beta * mu / 2.
    --membrane springs: anima's network itself, one VBD spring per mesh edge, k = E A0 / L0, kd = 0.01 k (N s/m,
      VBD's spring damping is exactly that), no membrane; Newton's springs also push when compressed.
  bending: VBD's dihedral element E = 1/2 ke L0 (theta - theta0)^2, damping kd L0 theta_dot; per edge
      ke = k_b L0 / (4 (A1 + A2)) (Bridson's element in the small-angle limit: k_b/(4h) on axis edges,
      k_b/(2 sqrt2 h) on diagonals, k_b = 1e-3), kd = 1e-4 (anima's k_d |e| theta_dot, the same form).
  air drag: VBD has none for particles; C_i/m_i = 5 1/s everywhere, so after every step the velocities are scaled
      by exp(-5 dt) (operator splitting of -C_i v_i, exact for the drag alone; a Warp kernel inside the timed loop).
  contact: VBD's soft particle-shape contact, particle radius --radius (default min(2 mm, h/4)) plus the shape's
      margin 0; penalty ke --contact-ke (default 1e4 N/m), kd --contact-kd (default 0: implicit Euler leaves no
      bounce, restitution ~0), friction 0.3 (Newton averages the model's soft_contact_mu and the shape's mu; both 0.3).
      Solver-owned CollisionPipeline, detection gap --contact-gap (default 2 cm, about v dt at the drag's terminal
      speed), run inside each step on VBD's AUTO schedule.
  self-contact: on by default (VBD's vertex-triangle and edge-edge contact with DAT truncation, which runs on
      the CPU), margin --self-margin (default min(2 mm, h/4)), friction 0.3; --no-self-contact turns it off.
      Its Divide-and-Truncate step keeps every particle within 0.5 * 0.85 * (margin + gap) of where it was at the
      last detection, the inertial prediction included: that caps the speed at 0.425 (margin + gap)/dt. The
      detection gap --self-gap therefore defaults to what gives --self-speed-cap 2.5 m/s (above g/5 = 1.96 m/s,
      the drag's terminal speed): about 9.6 cm at 1/60 s, so the rest-shape exclusion radius (--self-exclusion)
      defaults to margin + gap, and pairs that are that close in the flat sheet never collide. A small gap at
      1/60 s freezes the fall instead (gap = margin = 2 mm: 0.1 m/s).
Timing: `wall_s` is the loop of steps alone, after model build, kernel compilation and two warm-up steps (on a
copy of the state, then discarded). The loop runs in chunks of --chunk steps; between chunks the largest speed is
read (outside the timed part). CPU graph capture is not used (Warp captures graphs on CUDA devices only).
"""
import argparse, math, os, sys, time
import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import drape_common as D

ap = D.add_common_args(argparse.ArgumentParser(description=__doc__.split("\n")[0]))
ap.add_argument("--iters", type=int, default=10, help="VBD iterations per step")
ap.add_argument("--membrane", choices=["fem", "springs"], default="fem")
ap.add_argument("--tri-ke", type=float, help="membrane mu, N/m (default: the network's equivalent)")
ap.add_argument("--tri-ka", type=float, help="membrane lambda, N/m (default: the network's equivalent)")
ap.add_argument("--tri-kd", type=float, help="membrane damping (default beta*mu/2, beta = 0.01 s)")
ap.add_argument("--bend-scale", type=float, default=1.0, help="x the Bridson-equivalent bending ke")
ap.add_argument("--bend-kd", type=float, default=D.BEND_D)
ap.add_argument("--radius", type=float, help="particle contact radius, m")
ap.add_argument("--contact-ke", type=float, default=1e4)
ap.add_argument("--contact-kd", type=float, default=0.0)
ap.add_argument("--contact-gap", type=float, default=0.02)
ap.add_argument("--full-surface-contact", action="store_true",
                help="also collide the cloth's edges and triangle interiors with the obstacles (Newton's "
                     "enable_rigid_soft_full_surface_contact); default: its vertices only")
ap.add_argument("--friction", type=float, default=D.FRICTION)
ap.add_argument("--no-self-contact", action="store_true")
ap.add_argument("--self-margin", type=float)
ap.add_argument("--self-gap", type=float,
                help="self-contact detection gap, m (default: what lets a particle move --self-speed-cap per step)")
ap.add_argument("--self-speed-cap", type=float, default=2.5,
                help="m/s: VBD's penetration-free truncation bounds each particle's motion per step to "
                     "0.5*0.85*(margin+gap); the default gap makes that bound this speed (2.5 > g/5, the drag's "
                     "terminal speed)")
ap.add_argument("--self-exclusion", type=float,
                help="rest-shape exclusion radius of self-contact, m (default margin + gap: pairs closer than it in "
                     "the flat rest shape never collide)")
ap.add_argument("--self-detect-every", type=int, default=0,
                help="self-contact detection before every K-th VBD iteration (0: VBD's AUTO schedule)")
ap.add_argument("--no-drag", action="store_true", help="leave the air drag out")
a = ap.parse_args()

import warp as wp
wp.config.quiet = True
import newton

wp.set_device("cpu")
t_build = time.perf_counter()
V = a.V
h, bm, x0, tris, eq = D.cloth_setup(V, a.obstacle)
radius = a.radius if a.radius is not None else min(2e-3, h / 4)
self_margin = a.self_margin if a.self_margin is not None else min(2e-3, h / 4)
RELAX = 0.85  # SolverVBD's dat_conservative_bound_relaxation default
self_gap = a.self_gap if a.self_gap is not None else max(self_margin, 2 * a.self_speed_cap * a.dt / RELAX - self_margin)
self_excl = a.self_exclusion if a.self_exclusion is not None else self_margin + self_gap
if a.membrane == "fem":
    tri_ke = a.tri_ke if a.tri_ke is not None else eq["mu"]
    tri_ka = a.tri_ka if a.tri_ka is not None else eq["lam"]
    tri_kd = a.tri_kd if a.tri_kd is not None else D.DAMP_RATIO * tri_ke / 2.0
else:
    tri_ke = tri_ka = tri_kd = 0.0

b = newton.ModelBuilder(gravity=(0.0, 0.0, -D.G * a.gravity_scale))
cfg = b.default_shape_cfg
cfg.mu = a.friction
cfg.ke = a.contact_ke
cfg.kd = a.contact_kd
cfg.restitution = 0.0
if a.obstacle == "bunny":
    verts, ftri = bm
    mesh = newton.Mesh(verts.astype(np.float32), ftri.ravel().astype(np.int32))
    b.add_shape_mesh(-1, mesh=mesh, label="bunny")
else:
    b.add_shape_sphere(-1, xform=wp.transform(wp.vec3(*D.SPHERE_C), wp.quat_identity()), radius=D.SPHERE_R,
                       label="sphere")
b.add_ground_plane()
b.add_cloth_mesh(pos=wp.vec3(0.0, 0.0, 0.0), rot=wp.quat_identity(), scale=1.0, vel=wp.vec3(0.0, 0.0, 0.0),
                 vertices=[wp.vec3(*p) for p in x0], indices=tris.ravel().tolist(), density=D.RHO_A,
                 tri_ke=tri_ke, tri_ka=tri_ka, tri_kd=tri_kd, edge_ke=1.0, edge_kd=a.bend_kd,
                 particle_radius=radius, label="cloth")
if a.membrane == "springs":
    se, _, sk, skd = D.springs(V)
    for (i, j), k, kd in zip(se, sk, skd):
        b.add_spring(int(i), int(j), float(k), float(kd), 0.0)
b.color(include_bending=True)
model = b.finalize(device="cpu")
# per-edge bending stiffness: Bridson's small-angle hinge per unit length (boundary edges have no hinge)
ei = model.edge_indices.numpy()
ebp = model.edge_bending_properties.numpy()
interior = (ei[:, 0] >= 0) & (ei[:, 1] >= 0)
ke_edge = np.zeros(len(ei))
ke_edge[interior] = a.bend_scale * D.hinge_bending_per_length(x0, ei[interior])
ebp[:, 0] = ke_edge
ebp[:, 1] = np.where(interior, a.bend_kd, 0.0)
model.edge_bending_properties.assign(ebp.astype(np.float32))
mass_err = float(np.abs(model.particle_mass.numpy() - D.masses(V)).max())
model.soft_contact_ke = a.contact_ke
model.soft_contact_kd = a.contact_kd
model.soft_contact_mu = a.friction

pipeline = newton.CollisionPipeline(model, soft_contact_gap=a.contact_gap,
                                    enable_rigid_soft_full_surface_contact=a.full_surface_contact)
kw = {}
if not a.no_self_contact:
    kw = dict(particle_enable_self_contact=True, particle_self_contact_margin=self_margin,
              particle_self_contact_gap=self_gap,
              particle_rest_shape_contact_exclusion_radius=self_excl)
    if a.self_detect_every > 0:
        slot = newton.solvers.SolverBase.CollisionSlot.SOFT_SELF_CONTACT
        kw["collision_frequency"] = {slot: a.self_detect_every}
        kw["collision_frequency_type"] = {slot: newton.solvers.SolverBase.CollisionFrequencyType.ITERATIONS}
solver = newton.solvers.SolverVBD(model, iterations=a.iters, collision_pipeline=pipeline, **kw)
s0, s1 = model.state(), model.state()
ctrl = model.control()
steps = D.n_steps(a.duration, a.dt)
drag = 0.0 if a.no_drag else math.exp(-D.DRAG_RATE * a.dt)


@wp.kernel
def scale_velocity(qd: wp.array[wp.vec3], s: float):
    i = wp.tid()
    qd[i] = qd[i] * s


def simulate(n):
    global s0, s1
    for _ in range(n):
        s0.clear_forces()
        solver.step(s0, s1, ctrl, None, a.dt)
        if drag:
            wp.launch(scale_velocity, dim=model.particle_count, inputs=[s1.particle_qd, drag], device="cpu")
        s0, s1 = s1, s0


build_s = time.perf_counter() - t_build
# warm-up (kernel compilation) on the initial state, then put it back
tc = time.perf_counter()
keep = [(arr, arr.numpy().copy()) for st in (s0, s1) for arr in (st.particle_q, st.particle_qd)]
simulate(2)
wp.synchronize_device("cpu")
for arr, val in keep:
    arr.assign(val)
compile_s = time.perf_counter() - tc

wall = 0.0
done = 0
vmax_run = 0.0
err = None
try:
    while done < steps:
        n = min(a.chunk, steps - done)
        t0 = time.perf_counter()
        simulate(n)
        wp.synchronize_device("cpu")
        wall += time.perf_counter() - t0
        done += n
        v = s0.particle_qd.numpy()
        sp = float(np.sqrt((v.astype(np.float64) ** 2).sum(1)).max())
        vmax_run = max(vmax_run, sp) if math.isfinite(sp) else float("nan")
        if not math.isfinite(sp) or sp > 1e3:
            break  # diverged: stop early, report as unstable
except Exception as e:  # noqa: BLE001
    err = repr(e)[:300]

x = s0.particle_q.numpy().astype(np.float64)
v = s0.particle_qd.numpy().astype(np.float64)
D.save_positions(a.save, x)
variant = (f"vbd {a.membrane} iters={a.iters} self_contact={'off' if a.no_self_contact else 'on'}"
           + ("" if drag else " no_drag"))
rec = D.drape_record("newton", variant, a, done, wall, x, v, vmax_run, bm, {
    "steps_planned": steps, "error": err, "build_s": build_s, "compile_s": compile_s,
    "params": {"tri_ke": tri_ke, "tri_ka": tri_ka, "tri_kd": tri_kd,
               "edge_ke_axis": float(D.BEND_K / (4 * h)) * a.bend_scale, "edge_kd": a.bend_kd,
               "radius": radius, "contact_ke": a.contact_ke, "contact_kd": a.contact_kd,
               "contact_gap": a.contact_gap, "friction": a.friction,
               "self_margin": None if a.no_self_contact else self_margin,
               "self_gap": None if a.no_self_contact else self_gap,
               "self_exclusion": None if a.no_self_contact else self_excl,
               "self_speed_cap": None if a.no_self_contact else 0.5 * RELAX * (self_margin + self_gap) / a.dt,
               "drag_factor_per_step": drag, "mass_max_abs_err": mass_err},
    "device": "cpu", "newton": newton.__version__, "warp": wp.config.version})
if done < steps:
    rec["stable"] = False
D.emit(rec)
