"""The drapes of benchmarks.md in MuJoCo 4.0: the cloth a 2D flex, integrator `discrete` (MuJoCo's implicit step;
MuJoCo 4.0 refuses flex elasticity under `implicit`/`implicitfast`), solver CG by default.

usage: drape_mujoco.py V [DT] --obstacle bunny|sphere [--duration S] [--save final.npy] [--gravity-scale G]
                       [--bunny-collision hull|prisms] [--selfcollide none|auto|bvh|sap|narrow] ...

Scene: drape_common.py. The cloth is `<flexcomp type="direct" dim="2">` with anima's own vertices and triangles
(one body with 3 slide joints per vertex, in grid order), the floor a plane geom, the sphere a sphere geom (exact).
The Bunny is a mesh geom of assets/meshes/bunny.obj placed as anima places it, but MuJoCo collides a mesh geom as its
CONVEX HULL: with --bunny-collision hull (default) the cloth drapes over the hull (no gap between the ears, no
hollow under the chin). --bunny-collision prisms instead adds one small convex geom per Bunny triangle (the triangle
and its copy pushed --prism-depth inwards along its normal; their union is a shell that follows the real surface).
--bunny-collision flex makes the Bunny a rigid 2D flex (`rigid="true"`, radius --bunny-radius), MuJoCo's documented
way to collide with a non-convex mesh (cloth-Bunny contacts are then flex-flex element pairs).
Solver: CG by default (MuJoCo's docs recommend Newton for cloth under `discrete`, but here CG was 5x faster at V = 65
and within 5 mm of its centre of mass after 0.5 s); at V = 129 both warn every step that the effective-metric
(M + h^2 K) solve did not converge (mjWARN_INERTIA, counted in `warnings`).

Material mapping (anima's Oliveira model -> MuJoCo flex, overridable by flags):
  membrane: `<elasticity elastic2d="both">` is a linear-elastic (StVK) membrane + discrete plate bending; its
      young*thickness and poisson are set to the spring network's isotropic equivalent (drape_common.py):
      E t = (2 + sqrt2)/3 * E A0 / h, nu = 1/3 (1821, 3641, 7283 N/m for V = 65, 129, 257).
      (Checked numerically: MuJoCo's membrane stiffness is exactly E t/(1-nu^2) in uniaxial strain.) Unlike the
      springs it resists compression.
  bending: MuJoCo's plate stiffness is D = E t^3 / (12 (1 - nu^2)) (also checked numerically); the thickness is
      chosen so that D = 3 k_b/8 = 3.75e-4 N m, the orientation average of anima's Bridson hinges (drape_common.py):
      t = sqrt(12 (1 - nu^2) D / (E t)) (1.48 mm at V = 65), young = (E t)/t.
  damping: `damping` = 0.01 s, MuJoCo's Rayleigh (stiffness-proportional) coefficient = anima's k_d/k (whether it
      also damps the bending was not checked; anima: k_d/k_b = 0.1 s on the hinges).
  masses: the vertex bodies get anima's lumped masses (1/3 of the adjacent triangle areas * 0.6 kg/m^2; flexcomp
      itself would spread the mass uniformly), then mj_setConst.
  air drag: each vertex's three slide dofs get damping C_i = 3 * area_i N s/m (exactly anima's -C_i v_i; MuJoCo's
      integrators treat dof damping implicitly).
  contact: flex radius --radius (default min(2 mm, h/4)), condim 3, friction 0.3 (cloth and geoms), MuJoCo's default
      soft contact (solref 0.02 1, critically damped, and implicit under `discrete`: no bounce).
  self-contact: --selfcollide (default auto: sweep-and-prune mid-phase for a 2D flex's element pairs); `none` turns
      it off.
Timing: `wall_s` is the loop of steps alone (mj_step in chunks of --chunk steps, the largest speed read between
chunks outside the timed part), after the model is compiled and one mj_forward.
"""
import argparse, math, os, sys, time
import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import drape_common as D

ap = D.add_common_args(argparse.ArgumentParser(description=__doc__.split("\n")[0]))
ap.add_argument("--integrator", default="discrete")
ap.add_argument("--solver", default="CG")
ap.add_argument("--iterations", type=int, help="constraint solver iterations (MuJoCo default 100)")
ap.add_argument("--bunny-collision", choices=["hull", "flex", "prisms"], default="hull")
ap.add_argument("--bunny-radius", type=float, default=1e-3, help="m, collision radius of the rigid Bunny flex")
ap.add_argument("--prism-depth", type=float, default=0.01, help="m, inward depth of the per-triangle prisms")
ap.add_argument("--selfcollide", default="auto", choices=["none", "auto", "bvh", "sap", "narrow"])
ap.add_argument("--radius", type=float, help="flex collision radius, m")
ap.add_argument("--young", type=float, help="Pa (default: the network's E t divided by the thickness)")
ap.add_argument("--poisson", type=float, default=1.0 / 3.0)
ap.add_argument("--thickness", type=float, help="m (default: what makes D = 3 k_b/8)")
ap.add_argument("--damping", type=float, default=D.DAMP_RATIO, help="Rayleigh coefficient, s")
ap.add_argument("--friction", type=float, default=D.FRICTION)
ap.add_argument("--no-drag", action="store_true")
ap.add_argument("--print-xml", action="store_true")
a = ap.parse_args()
import mujoco

t_build = time.perf_counter()
V = a.V
h, bm, x0, tris, eq = D.cloth_setup(V, a.obstacle)
nu = a.poisson
Et = eq["Et"]
thick = a.thickness if a.thickness is not None else math.sqrt(12 * (1 - nu * nu) * D.PLATE_D / Et)
young = a.young if a.young is not None else Et / thick
radius = a.radius if a.radius is not None else min(2e-3, h / 4)
fr = f"{a.friction:g} 0.005 0.0001"


def fmt(arr):
    return " ".join(f"{v:.9g}" for v in np.asarray(arr).ravel())


assets, geoms = [], []
if a.obstacle == "bunny":
    bv, bf = bm
    if a.bunny_collision == "hull":
        assets.append(f'<mesh name="bunny" vertex="{fmt(bv)}" face="{fmt(bf)}"/>')
        geoms.append(f'<geom name="bunny" type="mesh" mesh="bunny" friction="{fr}" rgba=".8 .6 .5 1"/>')
    elif a.bunny_collision == "flex":
        geoms.append(f'<flexcomp name="bunny" type="direct" dim="2" rigid="true" point="{fmt(bv)}" element="{fmt(bf)}" '
                     f'radius="{a.bunny_radius!r}" rgba=".8 .6 .5 1"><contact condim="3" friction="{fr}" '
                     f'selfcollide="none"/><edge equality="false"/></flexcomp>')
    else:
        A, B, C = bv[bf[:, 0]], bv[bf[:, 1]], bv[bf[:, 2]]
        n = np.cross(B - A, C - A)
        n /= np.linalg.norm(n, axis=1, keepdims=True)
        for i in range(len(bf)):
            P = np.stack([A[i], B[i], C[i]])
            Q = np.concatenate([P, P - a.prism_depth * n[i]])
            assets.append(f'<mesh name="p{i}" vertex="{fmt(Q)}"/>')
            geoms.append(f'<geom type="mesh" mesh="p{i}" friction="{fr}" rgba=".8 .6 .5 1"/>')
else:
    geoms.append(f'<geom name="sphere" type="sphere" size="{D.SPHERE_R}" pos="{fmt(D.SPHERE_C)}" friction="{fr}"/>')
g = -D.G * a.gravity_scale
iters = f' iterations="{a.iterations}"' if a.iterations else ""
xml = f"""
<mujoco model="drape">
  <compiler autolimits="true"/>
  <option timestep="{a.dt!r}" integrator="{a.integrator}" solver="{a.solver}" gravity="0 0 {g!r}"{iters}/>
  <size memory="4G"/>
  <asset>
    {chr(10).join(assets)}
  </asset>
  <worldbody>
    <geom name="floor" type="plane" size="0 0 1" friction="{fr}"/>
    {chr(10).join(geoms)}
    <flexcomp name="cloth" type="direct" dim="2" point="{fmt(x0)}" element="{fmt(tris)}" mass="{D.RHO_A * D.SIZE ** 2}"
              radius="{radius!r}">
      <contact selfcollide="{a.selfcollide}" condim="3" friction="{fr}"/>
      <elasticity young="{young!r}" poisson="{nu!r}" thickness="{thick!r}" elastic2d="both" damping="{a.damping!r}"/>
      <edge equality="false"/>
    </flexcomp>
  </worldbody>
</mujoco>"""
if a.print_xml:
    print(xml if len(xml) < 20000 else xml[:20000] + " ...")
m = mujoco.MjModel.from_xml_string(xml)
d = mujoco.MjData(m)
# vertex bodies, dofs: flexcomp keeps the point order
fc = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_FLEX, "cloth")
vb = m.flex_vertbodyid[m.flex_vertadr[fc]:m.flex_vertadr[fc] + m.flex_vertnum[fc]]
assert len(vb) == V * V
mass = D.masses(V)
m.body_mass[vb] = mass
dofs = np.empty((V * V, 3), dtype=int)
for i, b in enumerate(vb):
    j0 = m.body_jntadr[b]
    assert m.body_jntnum[b] == 3
    dofs[i] = m.jnt_dofadr[j0:j0 + 3]
if not a.no_drag:
    m.dof_damping[dofs.ravel()] = np.repeat(D.PERMEABILITY * D.vertex_areas(V), 3)
mujoco.mj_setConst(m, d)
mujoco.mj_forward(m, d)
cv = slice(m.flex_vertadr[fc], m.flex_vertadr[fc] + m.flex_vertnum[fc])
assert np.allclose(d.flexvert_xpos[cv], x0, atol=1e-9), "vertex order changed"
steps = D.n_steps(a.duration, a.dt)
build_s = time.perf_counter() - t_build

wall = 0.0
done = 0
vmax_run = 0.0
err = None
ncon_max = 0
while done < steps:
    n = min(a.chunk, steps - done)
    t0 = time.perf_counter()
    try:
        mujoco.mj_step(m, d, nstep=n)
    except Exception as e:  # noqa: BLE001
        err = repr(e)[:300]
        wall += time.perf_counter() - t0
        break
    wall += time.perf_counter() - t0
    done += n
    ncon_max = max(ncon_max, int(d.ncon))
    sp = float(np.linalg.norm(d.qvel[dofs], axis=1).max())
    vmax_run = max(vmax_run, sp) if math.isfinite(sp) else float("nan")
    if not math.isfinite(sp) or sp > 1e3:
        break
mujoco.mj_forward(m, d)
x = d.flexvert_xpos[cv].copy()
v = d.qvel[dofs].copy()
D.save_positions(a.save, x)
nc = int(d.ncon)
cf = d.contact.flex[:nc]
contacts_end = {"cloth_geom": int(((cf[:, 0] == fc) & (cf[:, 1] < 0) | (cf[:, 1] == fc) & (cf[:, 0] < 0)).sum()),
                "cloth_bunny_flex": int(((cf[:, 0] == fc) & (cf[:, 1] >= 0) & (cf[:, 1] != fc)
                                         | (cf[:, 1] == fc) & (cf[:, 0] >= 0) & (cf[:, 0] != fc)).sum()),
                "cloth_self": int(((cf[:, 0] == fc) & (cf[:, 1] == fc)).sum()),
                "selfcollide_setting": int(m.flex_selfcollide[fc])}
warn = {mujoco.mjtWarning(i).name: int(w.number) for i, w in enumerate(d.warning) if w.number}
variant = (f"flex {a.integrator}/{a.solver} selfcollide={a.selfcollide}"
           + (f" bunny={a.bunny_collision}" if a.obstacle == "bunny" else "") + (" no_drag" if a.no_drag else ""))
rec = D.drape_record("mujoco", variant, a, done, wall, x, v, vmax_run, bm, {
    "steps_planned": steps, "error": err, "build_s": build_s, "nv": int(m.nv), "ngeom": int(m.ngeom),
    "ncon_max_at_chunk_ends": ncon_max, "contacts_end": contacts_end, "warnings": warn,
    "params": {"Et": Et, "young": young, "poisson": nu, "thickness": thick,
               "plate_D": young * thick ** 3 / (12 * (1 - nu * nu)),
               "damping": a.damping, "radius": radius, "friction": a.friction, "drag": not a.no_drag},
    "mujoco": mujoco.__version__})
if done < steps or any(warn.get(w) for w in ("mjWARN_BADQACC", "mjWARN_BADQVEL", "mjWARN_BADQPOS")):
    rec["stable"] = False  # MuJoCo resets the state on divergence: count it as unstable
D.emit(rec)
