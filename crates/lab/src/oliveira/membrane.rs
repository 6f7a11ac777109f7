//! `cargo xtask reproduce membrane`: does refining the mesh converge? The standard sheet (1 m, 0.2 kg,
//! pinned at two corners, falling for 1 s) on uniform meshes 9 × 9, 17 × 17, 33 × 33 and 65 × 65, in
//! three cloth models: the standard sheet's springs (fixed k per spring), Oliveira's springs (k = E·A⁰/L0,
//! the thesis's scaling) and the continuum membrane of [`anima_cloth::membrane`]. Writes
//! `docs/reproduction/membrane.md` and `docs/figures/membrane-convergence.png`.
//!
//! The meshes share the 81 material points of the 9 × 9 grid (every (N − 1)/8-th vertex in each
//! direction); the distance between two meshes is the RMS distance over those points at a time. Every
//! run uses generalised-α at the same small step ([`STEP`], [`NEWTON_ITERATIONS`]), with the integration error measured on the finest mesh
//! (the step halved), so that what differs between two meshes is the mesh.

use std::fmt::Write as _;
use std::time::Instant;

use anima_cloth::membrane::{Membrane, MembraneSheetSpec};
use anima_cloth::spring_net::SheetSpec;
use anima_geom::DVec3;
use anima_ode::{Integrator, OdeSystem, State, Stepper};
use anima_viz::{LinePlot, Series, SeriesStyle};
use anyhow::{Result, bail};

use crate::repo::Repo;

/// Vertices per side of the meshes compared.
pub const SIZES: [usize; 4] = [9, 17, 33, 65];

/// Times at which the meshes are compared, s.
pub const TIMES: [f64; 3] = [0.25, 0.5, 1.0];

/// The step of every run, s: generalised-α's error at it is measured on the finest mesh (against the
/// step halved) and reported.
pub const STEP: f64 = 1.0 / 1000.0;

/// Newton iterations of every generalised-α step, all of them run. With the default (three, stopping
/// early once the updates contract) the membrane's integration error on the 65 × 65 mesh was 9.2 mm at
/// 0.5 s (1/1000 s against 1/2000 s); with six, 2.2 mm (both measured on a mesh with one diagonal
/// direction, before `MembraneSheetSpec` alternated them). The membrane's stiffness keeps each element's
/// rotation fixed, so Newton's method converges only linearly on it and needs the iterations; the
/// springs' errors change little (1.55 and 0.43 mm for the standard sheet).
pub const NEWTON_ITERATIONS: usize = 6;

/// A cloth model of the study.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Model {
    /// The standard sheet's springs: 1000, 500 and 10 N/m whatever the mesh.
    StandardSprings,
    /// Oliveira's springs: stretch and shear k = E·A⁰/L0 (E·A⁰ = 25 N), bend 10 N/m.
    OliveiraSprings,
    /// Co-rotational membrane and quadratic bending in
    /// [`anima_cloth::membrane::MembraneMaterial::STANDARD`].
    Membrane,
}

impl Model {
    pub const ALL: [Model; 3] = [Model::StandardSprings, Model::OliveiraSprings, Model::Membrane];

    pub fn label(self) -> &'static str {
        match self {
            Model::StandardSprings => "standard springs (fixed k)",
            Model::OliveiraSprings => "Oliveira springs (k = E·A⁰/L0)",
            Model::Membrane => "membrane (Y = 1000 N/m, ν = 0.3, k_b = 1e-3 N·m)",
        }
    }

    fn system(self, n: usize) -> Result<(Box<dyn OdeSystem<Coord = DVec3>>, Vec<DVec3>)> {
        Ok(match self {
            Model::StandardSprings => {
                let spec = SheetSpec::standard(n);
                (Box::new(spec.build()?), spec.positions())
            }
            Model::OliveiraSprings => {
                let spec = SheetSpec::oliveira_cloth(n);
                (Box::new(spec.build()?), spec.positions())
            }
            Model::Membrane => {
                let spec = MembraneSheetSpec::standard(n);
                let m: Membrane = spec.build()?;
                (Box::new(m), spec.positions())
            }
        })
    }
}

/// One run: the 81 shared material points at each of [`TIMES`], and its wall time.
#[derive(Debug, Clone)]
pub struct Run {
    pub points: Vec<Vec<DVec3>>,
    pub wall_s: f64,
}

/// Runs `model` on an n × n mesh with generalised-α at step `h` to the last of [`TIMES`].
pub fn run(model: Model, n: usize, h: f64) -> Result<Run> {
    if n < 9 || !(n - 1).is_multiple_of(8) {
        bail!("a {n} × {n} mesh does not hold the 9 × 9 material points");
    }
    let (mut sys, x0) = model.system(n)?;
    let mut stepper = Stepper::new(Integrator::GeneralizedAlpha, x0.len());
    stepper.set_newton_iterations(NEWTON_ITERATIONS);
    let mut now = State::new(x0.clone(), vec![DVec3::ZERO; x0.len()]);
    let mut next = now.clone();
    let stride = (n - 1) / 8;
    let sample =
        |x: &[DVec3]| -> Vec<DVec3> { (0..81).map(|k| x[(k / 9) * stride * n + (k % 9) * stride]).collect() };
    let mut points = Vec::new();
    let start = Instant::now();
    let mut t = 0.0;
    let mut step = 0usize;
    for &until in &TIMES {
        let steps = (until / h).round() as usize;
        while step < steps {
            stepper.step(sys.as_mut(), t, h, &now, &mut next)?;
            std::mem::swap(&mut now, &mut next);
            step += 1;
            t = step as f64 * h;
            if !now.x.iter().chain(&now.v).all(|p| p.is_finite()) {
                bail!(
                    "{} on {n} × {n}: the state went non-finite at step {step} (t = {t:.4} s)",
                    model.label()
                );
            }
        }
        points.push(sample(&now.x));
    }
    Ok(Run { points, wall_s: start.elapsed().as_secs_f64() })
}

/// RMS distance between two samples of the 81 points.
pub fn rms(a: &[DVec3], b: &[DVec3]) -> f64 {
    (a.iter().zip(b).map(|(p, q)| p.distance_squared(*q)).sum::<f64>() / a.len() as f64).sqrt()
}

/// The report: per model, each mesh's distance from the finest at each time, and the distance between
/// successive meshes.
pub fn reproduce(repo: &Repo) -> Result<()> {
    let mut doc = String::from(
        "# Mesh convergence of the cloth models\n\n_Generated by `cargo xtask reproduce membrane`; do not edit. \
         Single thread, release build, f64._\n\n\
         The standard sheet (1 m, 0.2 kg, pinned at the two corners of one edge, falling from flat under gravity) on \
         uniform meshes 9 × 9 … 65 × 65, in three models: the standard sheet's springs (1000, 500 and 10 N/m \
         whatever the mesh), Oliveira's springs (stretch and shear k = E·A⁰/L0 with E·A⁰ = 25 N, the thesis's \
         scaling, bend 10 N/m) and the continuum membrane of `anima_cloth::membrane` (co-rotational \
         constant-strain triangles, Y = E·t = 1000 N/m, ν = 0.3; quadratic discrete-shell bending, k_b = 10⁻³ N·m; \
         stiffness-proportional damping 10⁻³ s). The meshes share the 81 material points of the 9 × 9 grid; a \
         distance is the RMS distance over them. Every run is generalised-α at 1/1000 s; its integration error \
         (the finest mesh against the same at 1/2000 s) is given beside each model, so that what remains is the \
         mesh's.\n\n\
         A model whose refinement converges shows distances from the finest mesh that shrink as the mesh is \
         refined, and successive meshes that approach one another (the ratio of successive distances about ½ for a \
         first-order, ¼ for a second-order discretisation). A spring network need not: its stiffness to bending and \
         to shear depends on the mesh. Two limits hold by construction. The standard sheet's bend springs of fixed \
         k across two cells resist bending less and less as the cells shrink (their rigidity goes as k·h²), so its \
         meshes approach a membrane that does not resist bending at all, not the sheet of the coarse mesh. \
         Oliveira's springs stiffen as 1/L0, so its meshes approach an inextensible sheet. Only the membrane \
         model keeps one material, with one bending rigidity, on every mesh; its sheet alternates the cells' \
         diagonals like a chequerboard, so that the mesh is symmetric under the sheet's reflections.\n\n",
    );
    let mut plot = LinePlot::new(
        "Distance from the 65 × 65 mesh at t = 0.5 s",
        "vertices per side",
        "RMS distance over the 81 shared points (m)",
    );
    plot.log_x = true;
    plot.log_y = true;
    for model in Model::ALL {
        let mut runs = Vec::new();
        for &n in &SIZES {
            eprintln!("anima-lab: {} on {n} × {n} …", model.label());
            runs.push(run(model, n, STEP)?);
        }
        let finest = runs.last().expect("four meshes");
        eprintln!("anima-lab: {} on 65 × 65 at half the step …", model.label());
        let halved = run(model, *SIZES.last().expect("sizes"), STEP / 2.0)?;
        let _ = writeln!(doc, "## {}\n", model.label());
        let _ = write!(doc, "| mesh | wall time |");
        for t in TIMES {
            let _ = write!(doc, " from 65 × 65 at {t} s |");
        }
        let _ = write!(doc, " from the next finer at 0.5 s |\n|---|---|");
        for _ in TIMES {
            let _ = write!(doc, "---|");
        }
        doc.push_str("---|\n");
        let mut series = Vec::new();
        for (k, (n, r)) in SIZES.iter().zip(&runs).enumerate() {
            let _ = write!(doc, "| {n} × {n} | {:.2} s |", r.wall_s);
            for (ti, _) in TIMES.iter().enumerate() {
                if k + 1 == SIZES.len() {
                    let _ = write!(doc, " — |");
                } else {
                    let _ = write!(doc, " {:.1} mm |", rms(&r.points[ti], &finest.points[ti]) * 1e3);
                }
            }
            match runs.get(k + 1) {
                Some(next) => {
                    let _ = writeln!(doc, " {:.1} mm |", rms(&r.points[1], &next.points[1]) * 1e3);
                }
                None => doc.push_str(" — |\n"),
            }
            if k + 1 < SIZES.len() {
                series.push((*n as f64, rms(&r.points[1], &finest.points[1]).max(1e-6)));
            }
        }
        let _ = write!(doc, "\nIntegration error (65 × 65, 1/1000 s against 1/2000 s):");
        for (ti, t) in TIMES.iter().enumerate() {
            let _ = write!(doc, " {:.2} mm at {t} s;", rms(&finest.points[ti], &halved.points[ti]) * 1e3);
        }
        doc.pop();
        doc.push_str(".\n\n");
        plot.series.push(Series::new(model.label(), series, SeriesStyle::LineWithMarkers));
    }
    doc.push_str("![convergence](../figures/membrane-convergence.png)\n");
    repo.write_figure("membrane-convergence.png", &plot.render(900, 600)?)?;
    repo.write_text("docs/reproduction/membrane.md", &doc)?;
    print!("{doc}");
    Ok(())
}
