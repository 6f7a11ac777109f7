//! Probe of one drape with the thesis's remesher: `TEST` = 1 | 2 | 3, `RULE` = min | literal, `T` = end
//! time (s), `UNIFORM` set for the static 17 × 17 mesh instead, `IMPLICIT` for backward Euler at 1/4000 s
//! (contact from the end-of-step velocity), `MEMBRANE` for the continuum model's forces, `SUBDIVISION` for the 1-to-4 remesher, `COARSEN=0` to turn `coarsen_simplification` off,
//! `REBUILDS` to print every rebuild. Prints the state every 10 ms of simulated
//! time (the smallest world area of a triangle over its rest area first), a rebuild that leaves a
//! triangle under 5 % of its rest area, the fastest particle's springs and bending elements whenever a
//! particle passes 20 m/s, and the remesher's counts.

use anima_cloth::oliveira::{AdaptiveCloth, ShortEdgeRule, StepRule};
use anima_lab::oliveira::TESTS;
use anima_lab::repo::Repo;
use anima_scene::oliveira::Remesher;

fn main() -> anyhow::Result<()> {
    let repo = Repo::here();
    let n: usize = std::env::var("TEST").ok().and_then(|s| s.parse().ok()).unwrap_or(2);
    let literal = std::env::var("RULE").is_ok_and(|s| s == "literal");
    let test = &TESTS[n - 1];
    let t_end: f64 = std::env::var("T").ok().and_then(|s| s.parse().ok()).unwrap_or(test.snapshots[3]);
    let uniform = std::env::var("UNIFORM").is_ok();
    let mut loaded = anima_scene::load_oliveira(&test.scene_path(&repo, if uniform { 17 } else { 5 }))?;
    loaded.scene.cloth.tracked_vertex = (0, 0);
    if let (false, StepRule::Provot { startup_dt_s, .. }) = (uniform, loaded.scene.time_step) {
        loaded.scene.time_step = StepRule::Provot { beta: 0.001, startup_dt_s };
    }
    if std::env::var("IMPLICIT").is_ok() {
        loaded.scene.integrator = anima_ode::Integrator::ImplicitEuler;
        loaded.scene.time_step = StepRule::Fixed { dt_s: 1.0 / 4000.0 };
        loaded.scene.options.contact_velocity = anima_cloth::oliveira::ContactVelocity::EndOfStep;
    }
    if std::env::var("MEMBRANE").is_ok() {
        let material = anima_lab::oliveira::adaptive::membrane_material(&loaded.scene.material);
        loaded.scene.options.membrane = Some(material);
    }
    let cloth = loaded.build()?;
    let short_edge = if literal { ShortEdgeRule::LiteralSquare } else { ShortEdgeRule::MinLength };
    let remesher = if std::env::var("SUBDIVISION").is_ok() {
        Remesher::Subdivision { interval_s: 1e-3 }
    } else {
        Remesher::Oliveira { test: n as u8, short_edge, interval_s: 1e-3 }
    };
    let method = remesher.method().map_err(anyhow::Error::msg)?;
    let method = match method {
        anima_cloth::oliveira::AdaptiveMethod::Oliveira(mut p) => {
            p.coarsen_simplification = std::env::var("COARSEN").map_or(true, |s| s != "0");
            anima_cloth::oliveira::AdaptiveMethod::Oliveira(p)
        }
        other => other,
    };
    let method = if uniform { anima_cloth::oliveira::AdaptiveMethod::Static } else { method };
    let mut c = AdaptiveCloth::new(cloth, loaded.scene.gravity_m_s2, method);
    let mut next = 0.0;
    let mut rebuilds = 0;
    while c.cloth().time() < t_end {
        let r = match c.step() {
            Ok(r) => r,
            Err(e) => {
                println!("failed: {e}");
                break;
            }
        };
        let cl = c.cloth();
        if c.stats().rebuilds != rebuilds {
            rebuilds = c.stats().rebuilds;
            let (f, q) = worst(cl);
            if std::env::var("REBUILDS").is_ok() {
                let st = c.stats();
                println!(
                    "  rebuild t {:.4}: refinements {} simplifications {} next dt {:.2e} min edge {:.4}",
                    cl.time(),
                    st.refinements,
                    st.simplifications,
                    cl.dt(),
                    anima_cloth::oliveira::adaptive::min_rest_edge(cl.mesh())
                );
            }
            if q < 0.05 {
                println!(
                    "  rebuild at t {:.5}: worst area ratio {q:.3e} face {f} {:?}",
                    cl.time(),
                    cl.triangles()[f]
                );
            }
        }
        if cl.time() >= next || cl.max_speed() > 20.0 {
            let min_edge = anima_cloth::oliveira::adaptive::min_rest_edge(cl.mesh());
            let (_, q) = worst(cl);
            println!(
                "q {q:.2e} t {:.4} dt {:.2e} V {} F {} min edge {:.4} m_min {:.2e} k_max {:.1} vmax {:.2} KE {:.3e} inside {}",
                cl.time(),
                r.dt,
                cl.mesh().n_vertices(),
                cl.mesh().n_faces(),
                min_edge,
                cl.min_mass(),
                cl.max_stiffness(),
                cl.max_speed(),
                cl.kinetic_energy(),
                cl.penetrations().len()
            );
            next += 0.01;
            if cl.max_speed() > 20.0 {
                dump(cl);
            }
            if cl.max_speed() > 100.0 {
                break;
            }
        }
    }
    println!("steps {} {:?}", c.cloth().steps(), c.stats());
    Ok(())
}

fn dump(cl: &anima_cloth::oliveira::OliveiraCloth) {
    let x = cl.positions();
    let v = cl.velocities();
    let i = (0..v.len()).max_by(|&a, &b| v[a].length().total_cmp(&v[b].length())).unwrap();
    println!(
        "  fastest {i} |v| {:.2} m {:.2e} responded {}",
        v[i].length(),
        cl.masses()[i],
        cl.responded()[i]
    );
    let s = cl.springs();
    for (e, &[a, b]) in s.ends.iter().enumerate() {
        if a as usize == i || b as usize == i {
            let len = x[a as usize].distance(x[b as usize]);
            let other = if a as usize == i { b } else { a } as usize;
            println!(
                "  spring {a}-{b} L0 {:.4} len {:.4} k {:.1} (at {:.3}, other end at {:.3})",
                s.rest_length[e], len, s.stiffness[e], x[i], x[other]
            );
        }
    }
    for st in &cl.bending().stencils {
        if st.contains(&(i as u32)) {
            let p = st.map(|k| x[k as usize]);
            let e = p[3] - p[2];
            let n1 = (p[0] - p[2]).cross(p[0] - p[3]).length();
            let n2 = (p[1] - p[3]).cross(p[1] - p[2]).length();
            println!("  bend {st:?} |e| {:.4} |N1| {:.2e} |N2| {:.2e}", e.length(), n1, n2);
        }
    }
}

/// The face with the smallest signed world area over its rest area.
fn worst(cl: &anima_cloth::oliveira::OliveiraCloth) -> (usize, f64) {
    let x = cl.positions();
    let mut best = (0, f64::INFINITY);
    // Signed relative to the average normal of the cloth is not meaningful for folded cloth: use |N|.
    for (f, t) in cl.triangles().iter().enumerate() {
        let [a, b, c] = t.map(|k| x[k as usize]);
        let area = 0.5 * (b - a).cross(c - a).length();
        let q = area / cl.mesh().rest_area(f);
        if q < best.1 {
            best = (f, q);
        }
    }
    best
}
