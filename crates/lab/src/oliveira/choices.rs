//! `cargo xtask reproduce oliveira-choices` (and `oliveira`): the section of
//! `docs/reproduction/oliveira-results.md` that backs what `oliveira.md` says of the choices the thesis
//! leaves open — the scenes as the files load them, and each of anima's additions and readings run
//! beside the default on the drape it matters for: where the cloth is placed, re-testing the corrected
//! path, the bending floor under slivers, edge contacts, and friction on an incline.

use std::collections::BTreeSet;
use std::fmt::Write as _;
use std::ops::ControlFlow;

use anima_cloth::oliveira::{
    Centre, ClothDesc, Height, Material, ObjectDesc, OliveiraCloth, OliveiraScene, Options, ShapeDesc,
    StepRule,
};
use anima_geom::{Aabb, DVec2, DVec3, DiagonalPattern, Solid};
use anima_scene::oliveira::LoadedOliveira;
use anyhow::{Context, Result};

use super::{DrapeTest, Ended, TESTS, run_drape, unremeshed};
use crate::repo::Repo;

/// A particle is looked for inside an object every this many steps (and at the end).
const CHECK_EVERY: u64 = 50;

/// The slopes' μ of the incline runs: the threshold lies near tan 10° ≈ 0.176.
const INCLINE_MU: [f64; 7] = [0.4, 0.3, 0.2, 0.18, 0.15, 0.1, 0.05];

/// The incline's angle, degrees.
const INCLINE_DEGREES: f64 = 10.0;

/// A 10 cm square cloth (2 × 2 particles) lying on a horizontal floor under gravity tilted by
/// `degrees`: the same as a floor inclined by that angle, with the cloth already flat on it. Table
/// 5.1's material with friction `mu` for the cloth and the floor; RK4 at the thesis's step rule, 1 s.
pub fn incline(mu: f64, degrees: f64) -> OliveiraScene {
    let a = degrees.to_radians();
    OliveiraScene {
        duration_s: 1.0,
        gravity_m_s2: DVec3::new(9.81 * a.sin(), 0.0, -9.81 * a.cos()),
        cloth: ClothDesc {
            vertices_per_side: 2,
            size_m: 0.1,
            diagonals: DiagonalPattern::Uniform,
            centre: Centre::At(DVec2::ZERO),
            height: Height::At { z_m: 1e-4 },
            tracked_vertex: (0, 0),
        },
        material: Material { friction: mu, ..Material::table_5_1() },
        time_step: StepRule::Provot { beta: 0.008, startup_dt_s: Some(1e-4) },
        restitution: 0.5,
        objects: vec![ObjectDesc {
            name: "incline".into(),
            friction: mu,
            shape: ShapeDesc::HalfSpace { point_m: DVec3::ZERO, normal: DVec3::Z },
        }],
        integrator: anima_ode::Integrator::Rk4,
        options: Options::thesis(),
    }
}

/// What one run of a variant measured.
struct Watched {
    steps: u64,
    first_contact: Option<f64>,
    /// Particles found inside an object at any check.
    ever_inside: usize,
    /// The deepest a particle was found inside, m.
    deepest_m: f64,
    inside_at_end: usize,
    /// The smallest triangle area at any check over its rest area.
    least_area_ratio: f64,
    /// The smallest height of a triangle over one of its edges, over that edge's length, at any check.
    least_height_ratio: f64,
    tracked_end: DVec3,
    /// The state at the end.
    positions: Vec<DVec3>,
    velocities: Vec<DVec3>,
}

/// Runs `scene` (with the loaded meshes) to its end, looking inside the objects and at the triangles'
/// shapes every [`CHECK_EVERY`] steps and at the end.
fn watch(scene: &OliveiraScene, loaded: &LoadedOliveira) -> Result<Watched> {
    let cloth = OliveiraCloth::new(scene, loaded.meshes.iter().map(|(_, m)| m.clone()).collect())
        .context("building a variant of an Oliveira scene")?;
    let rest_areas: Vec<f64> = {
        let rest = cloth.mesh().rest();
        cloth
            .triangles()
            .iter()
            .map(|t| {
                let [a, b, c] = t.map(|i| rest[i as usize]);
                0.5 * (b - a).perp_dot(c - a).abs()
            })
            .collect()
    };
    let mut inside = BTreeSet::new();
    let (mut deepest, mut least_area, mut least_height) = (0.0f64, f64::INFINITY, f64::INFINITY);
    let mut look = |c: &OliveiraCloth| {
        for (i, k) in c.penetrations() {
            inside.insert(i);
            deepest = deepest.max(c.colliders()[k].solid.proximity(c.positions()[i]).distance);
        }
        let x = c.positions();
        for (t, &rest) in c.triangles().iter().zip(&rest_areas) {
            let [a, b, p] = t.map(|i| x[i as usize]);
            let twice_area = (b - a).cross(p - a).length();
            least_area = least_area.min(0.5 * twice_area / rest);
            for (u, v) in [(a, b), (b, p), (p, a)] {
                least_height = least_height.min(twice_area / u.distance_squared(v));
            }
        }
    };
    let mut adaptive = unremeshed(cloth, scene.gravity_m_s2);
    let ended = run_drape(&mut adaptive, scene.duration_s, |a, _, _| {
        if a.cloth().steps() % CHECK_EVERY == 0 {
            look(a.cloth());
        }
        ControlFlow::Continue(())
    });
    if let Ended::Failed(e) = ended {
        return Err(e).context("a variant of an Oliveira scene");
    }
    let cloth = adaptive.cloth();
    look(cloth);
    Ok(Watched {
        steps: cloth.steps(),
        first_contact: cloth.first_collision_time(),
        ever_inside: inside.len(),
        deepest_m: deepest,
        inside_at_end: cloth.penetrations().len(),
        least_area_ratio: least_area,
        least_height_ratio: least_height,
        tracked_end: cloth.tracked_position(),
        positions: cloth.positions().to_vec(),
        velocities: cloth.velocities().to_vec(),
    })
}

fn load(repo: &Repo, test: &DrapeTest, n: usize) -> Result<LoadedOliveira> {
    let path = test.scene_path(repo, n);
    anima_scene::load_oliveira(&path).with_context(|| format!("loading {}", path.display()))
}

/// The middle particle's height over the surface straight below it, m (the nearest object there).
fn height_over_object(cloth: &OliveiraCloth, n: usize) -> f64 {
    let p = cloth.positions()[(n / 2) * n + n / 2];
    cloth
        .colliders()
        .iter()
        .filter_map(|c| c.solid.ray_hit(p, -DVec3::Z, 10.0).map(|h| h.s))
        .fold(f64::INFINITY, f64::min)
}

fn vec3(v: DVec3) -> String {
    format!("({}, {}, {})", v.x, v.y, v.z)
}

/// An object as the scene describes it, with the loaded mesh's size.
fn describe(object: &ObjectDesc, loaded: &LoadedOliveira) -> String {
    match &object.shape {
        ShapeDesc::Mesh { file, up, length_m, base_centre_m } => {
            let mesh = loaded.meshes.iter().find(|(f, _)| f == file).map(|(_, m)| m);
            let size = mesh.map_or(String::new(), |m| {
                format!(" ({} vertices, {} triangles)", m.n_vertices(), m.n_triangles())
            });
            format!(
                "{}: `{file}`{size}, {up:?}-up turned to z-up, {length_m} m long, base centre at {} m",
                object.name,
                vec3(*base_centre_m)
            )
        }
        ShapeDesc::Sphere { centre_m, radius_m } => {
            format!("{}: sphere of radius {radius_m} m centred at {} m", object.name, vec3(*centre_m))
        }
        ShapeDesc::Cylinder { base_centre_m, radius_m, height_m } => format!(
            "{}: closed cylinder of radius {radius_m} m, {height_m} m thick, top at z = {} m, axis through ({}, {})",
            object.name,
            base_centre_m.z + height_m,
            base_centre_m.x,
            base_centre_m.y
        ),
        ShapeDesc::HalfSpace { point_m, normal } => {
            format!("{}: half-space through {} m, normal {}", object.name, vec3(*point_m), vec3(*normal))
        }
    }
}

fn cloth_placement(c: &ClothDesc) -> String {
    let centre = match c.centre {
        Centre::OverHighestPoint => "centred over the objects' highest point".to_owned(),
        Centre::At(p) => format!("centred at ({}, {})", p.x, p.y),
    };
    let height = match c.height {
        Height::AboveObjects { clearance_m } => format!("{clearance_m} m over that point"),
        Height::At { z_m } => format!("at z = {z_m} m"),
    };
    format!("{} m square, flat and at rest, {centre}, {height}", c.size_m)
}

/// The section's markdown.
pub fn section(repo: &Repo) -> Result<String> {
    let mut s = String::new();
    let _ = writeln!(s, "## The scenes, and what the choices the thesis leaves open change\n");
    let _ = writeln!(
        s,
        "`cargo xtask reproduce oliveira-choices` rewrites this section alone. [oliveira.md](oliveira.md) says why each default is what it is; here each switch runs beside the default on the drape it matters for (RK4 and the thesis's step rule, as in the tests above). Particles are looked for inside the objects every {CHECK_EVERY} steps and at the end.\n"
    );
    s.push_str(&scenes(repo)?);
    s.push_str(&placement(repo)?);
    let (text, fine) = corrected_path(repo)?;
    s.push_str(&text);
    let (text, coarse) = bending_floor(repo, &fine)?;
    s.push_str(&text);
    s.push_str(&edge_contacts(repo, &coarse)?);
    s.push_str(&friction()?);
    Ok(s + "\n")
}

/// The scenes as the files load them.
fn scenes(repo: &Repo) -> Result<String> {
    let mut s = String::from(
        "| test | objects | cloth | A⁰ (m²) | duration (s) | start-up Δt (s) |\n|---|---|---|---|---|---|\n",
    );
    for test in &TESTS {
        let loaded = load(repo, test, 5)?;
        let scene = &loaded.scene;
        let objects: Vec<String> = scene.objects.iter().map(|o| describe(o, &loaded)).collect();
        let startup = match scene.time_step {
            StepRule::Provot { startup_dt_s: Some(dt), .. } => format!("{dt:e}"),
            StepRule::Provot { startup_dt_s: None, .. } => "none".to_owned(),
            StepRule::Fixed { dt_s } => format!("fixed {dt_s:e}"),
        };
        let _ = writeln!(
            s,
            "| {} | {} | {} | {:e} | {} | {startup} |",
            test.roman(),
            objects.join("; "),
            cloth_placement(&scene.cloth),
            scene.material.cross_section_m2,
            scene.duration_s,
        );
    }
    Ok(s)
}

/// Test I's coarse cloth centred over the highest point (the default) and over the objects' bounding box.
fn placement(repo: &Repo) -> Result<String> {
    eprintln!("anima-lab: Oliveira choices: where the cloth is placed (Test I, 5 × 5) …");
    let test = &TESTS[0];
    let loaded = load(repo, test, 5)?;
    let bounded = loaded
        .build()?
        .colliders()
        .iter()
        .filter(|c| !matches!(c.solid, Solid::HalfSpace(_)))
        .fold(Aabb::EMPTY, |b, c| b.union(c.solid.aabb()));
    let centre = 0.5 * (bounded.min + bounded.max);
    let mut boxed = loaded.scene.clone();
    boxed.cloth.centre = Centre::At(DVec2::new(centre.x, centre.y));
    let mut s = format!(
        "\n**Where the cloth is placed** (Test I, 5 × 5; the thesis took {} steps):\n\n\
         | cloth centred over | middle particle over the object below it (cm) | first contact (s) | steps | particles inside at a check |\n\
         |---|---|---|---|---|\n",
        test.thesis[0].2
    );
    for (label, scene) in
        [("the highest point (default)", &loaded.scene), ("the objects' bounding box", &boxed)]
    {
        let n = scene.cloth.vertices_per_side;
        let at_rest = OliveiraCloth::new(scene, loaded.meshes.iter().map(|(_, m)| m.clone()).collect())?;
        let w = watch(scene, &loaded)?;
        let _ = writeln!(
            s,
            "| {label} | {:.1} | {} | {} | {} |",
            100.0 * height_over_object(&at_rest, n),
            w.first_contact.map_or("none".to_owned(), |t| format!("{t:.4}")),
            w.steps,
            w.ever_inside
        );
    }
    Ok(s)
}

/// Test I's fine drape with the corrected path re-tested (the default) and as printed; the default
/// run is handed on.
fn corrected_path(repo: &Repo) -> Result<(String, Watched)> {
    eprintln!("anima-lab: Oliveira choices: the corrected path re-tested or not (Test I, 17 × 17) …");
    let fine = load(repo, &TESTS[0], 17)?;
    let rechecked = watch(&fine.scene, &fine)?;
    let mut literal = fine.scene.clone();
    literal.options.recheck_corrected_path = false;
    let unchecked = watch(&literal, &fine)?;
    let mut s = format!(
        "\n**Re-testing the corrected path** (Test I, 17 × 17, to {} s):\n\n\
         | corrected path | particles inside at a check | deepest (cm) | inside at the end | steps |\n\
         |---|---|---|---|---|\n",
        fine.scene.duration_s
    );
    for (label, w) in [("re-tested (default)", &rechecked), ("as printed (Eq. 4.18 untested)", &unchecked)] {
        let _ = writeln!(
            s,
            "| {label} | {} | {:.1} | {} | {} |",
            w.ever_inside,
            100.0 * w.deepest_m,
            w.inside_at_end,
            w.steps
        );
    }
    Ok((s, rechecked))
}

/// The coarse drapes with the bending floor on (the default) and off, and the triangles' shapes on
/// them and on the fine Test I drape `fine`; the coarse default runs are handed on.
fn bending_floor(repo: &Repo, fine: &Watched) -> Result<(String, Vec<(&'static DrapeTest, Watched)>)> {
    eprintln!("anima-lab: Oliveira choices: the bending floor on and off (the 5 × 5 drapes) …");
    let mut same_bits = Vec::new();
    let mut coarse = Vec::new();
    for t in &TESTS {
        let loaded = load(repo, t, 5)?;
        let with = watch(&loaded.scene, &loaded)?;
        let mut off = loaded.scene.clone();
        off.options.bending_height_floor = 0.0;
        let without = watch(&off, &loaded)?;
        same_bits.push(with.positions == without.positions && with.velocities == without.velocities);
        coarse.push((t, with));
    }
    let least = |f: fn(&Watched) -> f64| coarse.iter().map(|(_, w)| f(w)).fold(f64::INFINITY, f64::min);
    let s = format!(
        "\n**The bending floor** (η = {}: a bending element's mode is scaled down where a triangle's height over its hinge is below η·|e|). The 5 × 5 drapes of Tests I, II and III end with the same bits with the floor off: {}. On those drapes the smallest triangle at a check has {:.0} % of its rest area and the thinnest a height of {:.2}·|e| over one of its edges; on the 17 × 17 Test I drape (the default run above) {:.0} % and {:.2}·|e|.\n\n",
        Options::BENDING_HEIGHT_FLOOR,
        if same_bits.iter().all(|&b| b) {
            "yes, all three".to_owned()
        } else {
            format!("**no** ({same_bits:?})")
        },
        100.0 * least(|w| w.least_area_ratio),
        least(|w| w.least_height_ratio),
        100.0 * fine.least_area_ratio,
        fine.least_height_ratio,
    );
    Ok((s, coarse))
}

/// The coarse drapes with edge contacts off (`coarse`, the default runs) and on.
fn edge_contacts(repo: &Repo, coarse: &[(&DrapeTest, Watched)]) -> Result<String> {
    eprintln!("anima-lab: Oliveira choices: edge contacts on (the 5 × 5 drapes) …");
    let mut s = String::from(
        "**Edge contacts** (`options.edge_contacts`), on the 5 × 5 drapes:\n\n\
         | test | edge contacts | particles inside at a check | inside at the end | P at the end (m) | steps |\n\
         |---|---|---|---|---|---|\n",
    );
    for (t, off) in coarse {
        let loaded = load(repo, t, 5)?;
        let mut scene = loaded.scene.clone();
        scene.options.edge_contacts = true;
        let on = watch(&scene, &loaded)?;
        for (label, w) in [("off (default)", off), ("on", &on)] {
            let p = w.tracked_end;
            let _ = writeln!(
                s,
                "| {} | {label} | {} | {} | ({:.2}, {:.2}, {:.2}) | {} |",
                t.roman(),
                w.ever_inside,
                w.inside_at_end,
                p.x,
                p.y,
                p.z,
                w.steps
            );
        }
    }
    Ok(s)
}

/// The cloth on the incline at each of [`INCLINE_MU`].
fn friction() -> Result<String> {
    eprintln!("anima-lab: Oliveira choices: friction on a {INCLINE_DEGREES}° incline …");
    let mut s = format!(
        "\n**Friction** (Eqs. 4.16–4.17): a 10 cm cloth resting flat under gravity tilted by {INCLINE_DEGREES}° (the same as a {INCLINE_DEGREES}° incline), μ the same for cloth and floor, {} s. Coulomb friction would hold it for μ ≥ tan {INCLINE_DEGREES}° = {:.3}.\n\n| μ | moved down the slope (mm) |\n|---|---|\n",
        incline(0.0, INCLINE_DEGREES).duration_s,
        INCLINE_DEGREES.to_radians().tan()
    );
    for mu in INCLINE_MU {
        let scene = incline(mu, INCLINE_DEGREES);
        let mut cloth = OliveiraCloth::new(&scene, vec![])?;
        let start = cloth.tracked_position();
        cloth.run_until(scene.duration_s).with_context(|| format!("the incline at μ = {mu}"))?;
        let _ = writeln!(s, "| {mu} | {:.2} |", 1e3 * (cloth.tracked_position() - start).x);
    }
    Ok(s)
}
