//! The eight FLEX3D experiments of Nedel 1993 (spec `flex3d.md` S6, E-1..E-8), each as a function that
//! runs it and returns what it measured. `cargo xtask reproduce` prints these beside the thesis's claims
//! and the integration tests assert the specification's criteria on the same numbers.

use std::path::PathBuf;

use anima_cloth::flex3d::mass_spring::{TABLE_4_1_STEPS, TABLE_4_1_THESIS, table_4_1};
use anima_cloth::flex3d::{
    ContactApproach, FLEX3D_GRAVITY, Flex3dWorld, FrictionMode, ModelOptions, TranslationMode,
};
use anima_cloth::self_collision::{SelfCollisionMode, SelfCollisionStats};
use anima_geom::{DVec3, count_self_intersections};
use anima_ode::Integrator;
use anima_scene::{LoadOptions, LoadedFlex3d};
use anyhow::Result;

pub mod report;

/// Folder of the thesis scripts, `assets/flex3d` in the repository.
pub fn flex3d_assets() -> PathBuf {
    crate::repo::Repo::here().assets("flex3d")
}

/// One thesis scene: its script and the gravity the thesis ran it with (spec S6.0).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ThesisScene {
    /// E-3, Fig. 6.2: curtain settling (gravity on).
    Curtain,
    /// E-4, Fig. 6.4 (repaired): paper projecting from a plane (gravity off).
    Paper,
    /// E-5, Fig. A2.2: surface in the wind (gravity off); also E-2.
    Wind,
    /// E-6, Fig. A2.4: theatre curtains (gravity on).
    TheatreCurtains,
    /// E-7, Fig. A2.6: stiff cardboard (gravity off).
    Cardboard,
    /// E-8, Fig. A2.8: tablecloth on a table (gravity off, the external force supplies the fall).
    Tablecloth,
}

impl ThesisScene {
    pub const ALL: [ThesisScene; 6] = [
        ThesisScene::Curtain,
        ThesisScene::Paper,
        ThesisScene::Wind,
        ThesisScene::TheatreCurtains,
        ThesisScene::Cardboard,
        ThesisScene::Tablecloth,
    ];

    pub fn script(self) -> &'static str {
        match self {
            ThesisScene::Curtain => "fig6-2-cortina.par",
            ThesisScene::Paper => "fig6-4-papel.par",
            ThesisScene::Wind => "a2-2-vento.par",
            ThesisScene::TheatreCurtains => "a2-4-cortinas.par",
            ThesisScene::Cardboard => "a2-6-papelao.par",
            ThesisScene::Tablecloth => "a2-8-toalha.par",
        }
    }

    /// Short name used for RON scenes and figures.
    pub fn slug(self) -> &'static str {
        match self {
            ThesisScene::Curtain => "curtain",
            ThesisScene::Paper => "paper",
            ThesisScene::Wind => "wind",
            ThesisScene::TheatreCurtains => "theatre-curtains",
            ThesisScene::Cardboard => "cardboard",
            ThesisScene::Tablecloth => "tablecloth",
        }
    }

    /// Gravity per spec S6.0.
    pub fn gravity(self) -> DVec3 {
        match self {
            ThesisScene::Curtain | ThesisScene::TheatreCurtains => FLEX3D_GRAVITY,
            _ => DVec3::ZERO,
        }
    }

    /// The frames the thesis's figure shows (where it says; otherwise an even spread).
    pub fn figure_frames(self) -> Vec<usize> {
        match self {
            ThesisScene::Curtain => vec![1, 25],
            ThesisScene::Paper | ThesisScene::Wind => (3..=19).step_by(2).collect(),
            ThesisScene::Cardboard => (3..=19).step_by(2).collect(),
            ThesisScene::TheatreCurtains => vec![1, 25, 35, 50, 65, 78, 90, 100, 110, 120, 130, 140, 145],
            ThesisScene::Tablecloth => vec![1, 2, 3, 4, 5, 6, 8, 12, 20],
        }
    }

    /// Where pictures of the scene look from: the sheets that leave their plane (+z) are seen from the
    /// side so that the motion out of the plane shows.
    pub fn view_dir(self) -> DVec3 {
        match self {
            ThesisScene::Paper | ThesisScene::Cardboard | ThesisScene::Wind => DVec3::new(-1.0, -0.35, -0.55),
            _ => crate::picture::VIEW_DIR,
        }
    }

    /// Loads the script with the thesis's gravity.
    pub fn load(self) -> Result<LoadedFlex3d> {
        Ok(anima_scene::load_flex3d(
            &flex3d_assets().join(self.script()),
            &LoadOptions { gravity: Some(self.gravity()) },
        )?)
    }

    /// A fresh world of the scene.
    pub fn world(self, edit: impl FnOnce(&mut LoadedFlex3d)) -> Result<(LoadedFlex3d, Flex3dWorld)> {
        let mut loaded = self.load()?;
        edit(&mut loaded);
        let world = Flex3dWorld::new(&loaded.scene, loaded.meshes())?;
        Ok((loaded, world))
    }
}

/// Runs `world` to the end of frame `k` of `loaded`.
pub fn run_to_frame(loaded: &LoadedFlex3d, world: &mut Flex3dWorld, k: usize) -> Result<()> {
    Ok(world.run_to_step(loaded.scene.frame_step(k) as u64)?)
}

// ---------------------------------------------------------------------------------------------- E-1

/// E-1: Table 4.1 recomputed, with how many of the 66 printed values it matches.
#[derive(Debug, Clone)]
pub struct Table41 {
    pub ours: [[f64; 6]; 11],
    pub thesis: [[f64; 6]; 11],
    pub steps: [f64; 6],
    pub matches: usize,
}

pub fn e1_table_4_1(integrator: Integrator) -> Table41 {
    let ours = table_4_1(integrator);
    let matches = (0..11)
        .flat_map(|t| (0..6).map(move |c| (t, c)))
        .filter(|&(t, c)| ours[t][c] == TABLE_4_1_THESIS[t][c])
        .count();
    Table41 { ours, thesis: TABLE_4_1_THESIS, steps: TABLE_4_1_STEPS, matches }
}

// ---------------------------------------------------------------------------------------------- E-2

/// E-2: frame 12 of the wind scene for each step, and its largest particle distance from the h = 0.001
/// result.
#[derive(Debug, Clone)]
pub struct E2StepSweep {
    pub steps: Vec<f64>,
    pub max_deviation: Vec<f64>,
    pub frames: Vec<Vec<DVec3>>,
    /// Width of the x–y bounding box at frame 12 for each step (18 at rest).
    pub xy_extent: Vec<f64>,
}

pub const E2_STEPS: [f64; 5] = [0.1, 0.05, 0.01, 0.005, 0.001];

pub fn e2_step_sweep(friction: FrictionMode) -> Result<E2StepSweep> {
    let mut frames = Vec::new();
    for h in E2_STEPS {
        let (loaded, mut world) = ThesisScene::Wind.world(|l| {
            l.scene.dt_s = h;
            l.scene.friction.mode = friction;
        })?;
        // A diverging run may leave finite bounds; a non-finite one counts as infinitely far.
        match run_to_frame(&loaded, &mut world, 12) {
            Ok(()) => frames.push(world.positions().to_vec()),
            Err(_) => frames.push(vec![DVec3::splat(f64::INFINITY); world.positions().len()]),
        }
    }
    let reference = frames.last().expect("five runs").clone();
    let max_deviation = frames
        .iter()
        .map(|f| f.iter().zip(&reference).map(|(a, b)| a.distance(*b)).fold(0.0, f64::max))
        .collect();
    let xy_extent = frames
        .iter()
        .map(|f| {
            let b = anima_geom::Aabb::from_points(f.iter().copied());
            b.size().x.max(b.size().y)
        })
        .collect();
    Ok(E2StepSweep { steps: E2_STEPS.to_vec(), max_deviation, frames, xy_extent })
}

// ---------------------------------------------------------------------------------------------- E-3

/// E-3: the curtain's maximum particle speed per frame and the bottom row's mean height.
#[derive(Debug, Clone)]
pub struct E3Curtain {
    pub max_speed: Vec<f64>,
    pub bottom_row_y: Vec<f64>,
}

pub fn e3_curtain(friction: FrictionMode) -> Result<E3Curtain> {
    let (loaded, mut world) = ThesisScene::Curtain.world(|l| l.scene.friction.mode = friction)?;
    let (mut max_speed, mut bottom_row_y) = (Vec::new(), Vec::new());
    let info = world.surfaces()[0].clone();
    for k in 1..=loaded.scene.n_frames() {
        run_to_frame(&loaded, &mut world, k)?;
        max_speed.push(world.diagnostics().max_speed);
        let x = world.surface_positions(0);
        let bottom = &x[(info.rows - 1) * info.cols..];
        bottom_row_y.push(bottom.iter().map(|p| p.y).sum::<f64>() / bottom.len() as f64);
    }
    Ok(E3Curtain { max_speed, bottom_row_y })
}

// ------------------------------------------------------------------------------------------ E-4, E-7

/// E-4 and E-7: a sheet peeling off its plane, pinned along one edge.
#[derive(Debug, Clone)]
pub struct PeelingSheet {
    /// Smallest z over the free particles at each frame.
    pub min_free_z: Vec<f64>,
    /// Mean y of the free particles at each frame.
    pub mean_free_y: Vec<f64>,
    /// Position of the free corner (0, 0) at each frame.
    pub corner: Vec<DVec3>,
    pub max_speed: Vec<f64>,
    /// Mean bend angle (π minus the angle between opposite arms, radians) over the interior, per frame:
    /// the smoothness that E-7 compares with E-4.
    pub mean_bend: Vec<f64>,
    /// Largest bend angle per frame (sharpest fold).
    pub max_bend: Vec<f64>,
    pub collisions_with_surfaces: u64,
}

pub fn peeling_sheet(scene: ThesisScene, friction: FrictionMode, collisions: bool) -> Result<PeelingSheet> {
    let (loaded, mut world) = scene.world(|l| {
        l.scene.friction.mode = friction;
        l.scene.options.collisions = collisions;
    })?;
    let info = world.surfaces()[0].clone();
    let free: Vec<usize> = (0..info.n_particles()).filter(|&p| !world.is_pinned(p)).collect();
    let mut out = PeelingSheet {
        min_free_z: vec![],
        mean_free_y: vec![],
        corner: vec![],
        max_speed: vec![],
        mean_bend: vec![],
        max_bend: vec![],
        collisions_with_surfaces: 0,
    };
    for k in 1..=loaded.scene.n_frames() {
        run_to_frame(&loaded, &mut world, k)?;
        let x = world.surface_positions(0);
        out.min_free_z.push(free.iter().map(|&p| x[p].z).fold(f64::INFINITY, f64::min));
        out.mean_free_y.push(free.iter().map(|&p| x[p].y).sum::<f64>() / free.len() as f64);
        out.corner.push(x[0]);
        out.max_speed.push(world.diagnostics().max_speed);
        let (mean, max) = bend_angles(x, info.rows, info.cols);
        out.mean_bend.push(mean);
        out.max_bend.push(max);
    }
    out.collisions_with_surfaces = world.collision_counts().with_surfaces;
    Ok(out)
}

/// Mean and largest bend angle π − ∠(a, P, b) over the horizontal and vertical opposite pairs.
pub fn bend_angles(x: &[DVec3], rows: usize, cols: usize) -> (f64, f64) {
    let (mut sum, mut max, mut n) = (0.0, 0.0f64, 0usize);
    let mut add = |p: usize, a: usize, b: usize| {
        let angle = (x[a] - x[p]).angle_between(x[b] - x[p]);
        let bend = std::f64::consts::PI - angle;
        sum += bend;
        max = max.max(bend);
        n += 1;
    };
    for i in 0..rows {
        for j in 0..cols {
            let p = i * cols + j;
            if j > 0 && j + 1 < cols {
                add(p, p - 1, p + 1);
            }
            if i > 0 && i + 1 < rows {
                add(p, p - cols, p + cols);
            }
        }
    }
    (sum / n.max(1) as f64, max)
}

// ---------------------------------------------------------------------------------------------- E-5

/// E-5: the sail held at three corners.
#[derive(Debug, Clone)]
pub struct E5Wind {
    /// z extent of the sheet at each frame.
    pub z_extent: Vec<f64>,
    /// Whether particle (9, 9), the free corner, has the largest z at each frame.
    pub free_corner_furthest: Vec<bool>,
    pub min_z: Vec<f64>,
    /// Self-collision responses up to each frame (the faithful response's).
    pub surface_hits: Vec<u64>,
    pub max_speed_last: f64,
    /// Largest particle speed at each frame.
    pub max_speed: Vec<f64>,
    /// Particle positions at the last frame.
    pub positions_last: Vec<DVec3>,
    /// The most crossing (edge, triangle) pairs of the sheet with itself after any step (not only at
    /// the frames), and the first step that ended with one.
    pub most_crossings: usize,
    pub first_crossing_step: Option<usize>,
    /// What the modern response did over the run (`None` unless it ran).
    pub modern: Option<SelfCollisionStats>,
}

/// E-5 as the thesis ran it, with its faithful self-collision response (`collisions`), or with
/// collisions off as the spec computed its numbers.
pub fn e5_wind(collisions: bool) -> Result<E5Wind> {
    e5_wind_with(|o| o.collisions = collisions)
}

/// E-5 with `edit` applied to the scene's options (the self-collision mode, say).
pub fn e5_wind_with(edit: impl FnOnce(&mut ModelOptions)) -> Result<E5Wind> {
    e5_wind_scene(|l| edit(&mut l.scene.options))
}

/// E-5 with `edit` applied to the loaded scene (options, friction, step).
pub fn e5_wind_scene(edit: impl FnOnce(&mut LoadedFlex3d)) -> Result<E5Wind> {
    let (loaded, mut world) = ThesisScene::Wind.world(edit)?;
    let info = world.surfaces()[0].clone();
    let corner = info.grid.index(9, 9);
    let triangles = world.all_triangles();
    let mut out = E5Wind {
        z_extent: vec![],
        free_corner_furthest: vec![],
        min_z: vec![],
        surface_hits: vec![],
        max_speed_last: 0.0,
        max_speed: vec![],
        positions_last: vec![],
        most_crossings: 0,
        first_crossing_step: None,
        modern: None,
    };
    for k in 1..=loaded.scene.n_frames() {
        while world.steps() < loaded.scene.frame_step(k) as u64 {
            world.step()?;
            let crossings = count_self_intersections(world.positions(), &triangles);
            if crossings > 0 {
                out.first_crossing_step.get_or_insert(world.steps() as usize);
                out.most_crossings = out.most_crossings.max(crossings);
            }
        }
        let x = world.surface_positions(0);
        let (lo, hi) =
            x.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), p| (l.min(p.z), h.max(p.z)));
        out.z_extent.push(hi - lo);
        out.min_z.push(lo);
        out.free_corner_furthest.push(x[corner].z == hi);
        out.surface_hits.push(world.collision_counts().with_surfaces);
        out.max_speed.push(world.diagnostics().max_speed);
    }
    out.max_speed_last = world.diagnostics().max_speed;
    out.positions_last = world.surface_positions(0).to_vec();
    out.modern = world.self_collision_stats();
    Ok(out)
}

// ---------------------------------------------------------------------------------------------- E-6

/// E-6: the theatre curtains.
#[derive(Debug, Clone)]
pub struct E6Theatre {
    pub frames: usize,
    /// Largest distance of a top-row particle from its start, per curtain, at the last frame.
    pub top_row_return_error: [f64; 2],
    /// Largest x displacement of the top rows at frame 78 (closed), per curtain.
    pub closed_displacement: [f64; 2],
    /// Whether `corte` in frames 1–25 is bit-identical to the E-3 curtain.
    pub matches_e3_first_25: bool,
    pub collisions_with_surfaces: u64,
    pub max_speed: Vec<f64>,
    pub max_out_of_plane: f64,
    /// Largest particle distance at frame 145 from the settled state of frame 25.
    pub distance_from_hanging: f64,
    /// Kinetic energy of both curtains at each frame.
    pub kinetic_energy: Vec<f64>,
}

pub fn e6_theatre() -> Result<E6Theatre> {
    e6_theatre_with(|_| {})
}

/// E-6 with `edit` applied to both the theatre scene and the E-3 curtain it is compared with.
pub fn e6_theatre_with(edit: impl Fn(&mut LoadedFlex3d)) -> Result<E6Theatre> {
    let (loaded, mut world) = ThesisScene::TheatreCurtains.world(&edit)?;
    let (c_loaded, mut curtain) = ThesisScene::Curtain.world(&edit)?;
    let infos = world.surfaces().to_vec();
    let top: Vec<Vec<usize>> = infos.iter().map(|s| (0..s.cols).map(|j| s.offset + j).collect()).collect();
    let start: Vec<DVec3> = world.positions().to_vec();
    let plane_z: Vec<f64> = infos.iter().map(|s| start[s.offset].z).collect();
    let mut matches = true;
    let mut closed = [0.0; 2];
    let mut max_speed = Vec::new();
    let mut kinetic_energy = Vec::new();
    let mut max_out_of_plane = 0.0f64;
    let mut hanging = Vec::new();
    for k in 1..=loaded.scene.n_frames() {
        run_to_frame(&loaded, &mut world, k)?;
        if k == 25 {
            hanging = world.positions().to_vec();
        }
        if k <= 25 {
            run_to_frame(&c_loaded, &mut curtain, k)?;
            matches &= world.surface_positions(0) == curtain.surface_positions(0);
        }
        if k == 78 {
            for c in 0..2 {
                closed[c] =
                    top[c].iter().map(|&p| (world.positions()[p].x - start[p].x).abs()).fold(0.0, f64::max);
            }
        }
        let d = world.diagnostics();
        max_speed.push(d.max_speed);
        kinetic_energy.push(d.kinetic_energy);
        for (s, z) in infos.iter().zip(&plane_z) {
            for p in s.range() {
                max_out_of_plane = max_out_of_plane.max((world.positions()[p].z - z).abs());
            }
        }
    }
    let mut ret = [0.0; 2];
    for c in 0..2 {
        ret[c] = top[c].iter().map(|&p| world.positions()[p].distance(start[p])).fold(0.0, f64::max);
    }
    Ok(E6Theatre {
        frames: loaded.scene.n_frames(),
        top_row_return_error: ret,
        closed_displacement: closed,
        matches_e3_first_25: matches,
        collisions_with_surfaces: world.collision_counts().with_surfaces,
        max_speed,
        max_out_of_plane,
        distance_from_hanging: world
            .positions()
            .iter()
            .zip(&hanging)
            .map(|(a, b)| a.distance(*b))
            .fold(0.0, f64::max),
        kinetic_energy,
    })
}

// ---------------------------------------------------------------------------------------- E-5, E-6

/// One reading of an ambiguity the thesis leaves open, as an edit of the loaded scene. Every reading
/// is a switch that already exists; the faithful defaults are untouched.
#[derive(Clone, Copy)]
pub struct Reading {
    /// What the reading changes, with the spec's ambiguity it answers.
    pub name: &'static str,
    pub edit: fn(&mut LoadedFlex3d),
}

impl std::fmt::Debug for Reading {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name)
    }
}

/// The readings searched for E-5: the self-collision response (A-3, S7.3 #4), friction (A-2, S3.7),
/// the wind, the step, and, for contrast, no self-collisions (the spec's numbers) and anima's
/// modern response.
pub const E5_READINGS: [Reading; 10] = [
    Reading { name: "faithful (spec defaults)", edit: |_| {} },
    Reading {
        name: "contact partner: all three vertices (A-3)",
        edit: |l| l.scene.options.contact = ContactApproach::ThreeVertices,
    },
    Reading {
        name: "friction viscous −μv (A-2)", edit: |l| l.scene.friction.mode = FrictionMode::Viscous
    },
    Reading { name: "friction clamp (S3.7 [EXT])", edit: |l| l.scene.options.friction_clamp = true },
    Reading {
        name: "three vertices and viscous friction",
        edit: |l| {
            l.scene.options.contact = ContactApproach::ThreeVertices;
            l.scene.friction.mode = FrictionMode::Viscous;
        },
    },
    Reading {
        name: "wind as an acceleration, 4.9 per particle (A-4)",
        edit: |l| l.scene.options.external_force_is_acceleration = true,
    },
    Reading { name: "Δt halved (0.0005)", edit: |l| l.scene.dt_s *= 0.5 },
    Reading {
        name: "all three vertices, Δt halved",
        edit: |l| {
            l.scene.options.contact = ContactApproach::ThreeVertices;
            l.scene.dt_s *= 0.5;
        },
    },
    Reading {
        name: "no self-collision (the spec's numbers)",
        edit: |l| l.scene.options.self_collision = SelfCollisionMode::Off,
    },
    Reading {
        name: "anima's modern response (not the thesis)",
        edit: |l| l.scene.options.self_collision = SelfCollisionMode::Modern,
    },
];

/// What one E-5 reading does to the sail.
#[derive(Debug, Clone)]
pub struct E5Row {
    pub reading: Reading,
    /// Largest particle speed over frames 3–20.
    pub peak_speed: f64,
    /// Largest particle speed at frame 20 (t = 4 s).
    pub last_speed: f64,
    /// The last frame up to which the free corner is furthest downwind at every frame from 3.
    pub leads_through: usize,
    /// z extent at frames 12 (before any contact; the spec's ≈ 46), 16 (its largest) and 20.
    pub extent_12: f64,
    pub extent_16: f64,
    pub extent_20: f64,
    /// Self-collision responses of the thesis's kind over the run.
    pub responses: u64,
    /// Largest particle distance at frame 20 from the run without self-collisions (how far contact
    /// moved the sail from the shape the wind alone gives it).
    pub distance_from_free: f64,
}

impl E5Row {
    /// The sail keeps its shape: the free corner leads at every frame the thesis shows (3–19) and no
    /// particle moves faster than 1.5 times the fastest of the run without self-collisions.
    pub fn keeps_shape(&self, free_peak_speed: f64) -> bool {
        self.leads_through >= 19 && self.peak_speed <= 1.5 * free_peak_speed
    }
}

/// Runs E-5 under each reading of [`E5_READINGS`].
pub fn e5_search() -> Result<Vec<E5Row>> {
    let free = e5_wind_scene(|l| l.scene.options.self_collision = SelfCollisionMode::Off)?;
    E5_READINGS
        .iter()
        .map(|&reading| {
            let w = e5_wind_scene(reading.edit)?;
            let distance_from_free = w
                .positions_last
                .iter()
                .zip(&free.positions_last)
                .map(|(a, b)| a.distance(*b))
                .fold(0.0, f64::max);
            Ok(E5Row {
                reading,
                peak_speed: w.max_speed[2..].iter().copied().fold(0.0, f64::max),
                last_speed: w.max_speed_last,
                leads_through: 2 + w.free_corner_furthest.iter().skip(2).take_while(|&&b| b).count(),
                extent_12: w.z_extent[11],
                extent_16: w.z_extent[15],
                extent_20: w.z_extent[19],
                responses: w.surface_hits.last().copied().unwrap_or(0),
                distance_from_free,
            })
        })
        .collect()
}

/// The readings searched for E-6: friction (A-2, S3.7), the translation's timing and the step.
/// No collision fires in E-6 and the curtains have no bending springs, so the contact readings and
/// the bend reaction cannot change it.
pub const E6_READINGS: [Reading; 5] = [
    Reading { name: "faithful (spec defaults)", edit: |_| {} },
    Reading {
        name: "friction viscous −μv (A-2)", edit: |l| l.scene.friction.mode = FrictionMode::Viscous
    },
    Reading { name: "friction clamp (S3.7 [EXT])", edit: |l| l.scene.options.friction_clamp = true },
    Reading {
        name: "translation as a jump per frame (A-6)",
        edit: |l| l.scene.options.translation = TranslationMode::PerFrameJump,
    },
    Reading { name: "Δt halved (0.0005)", edit: |l| l.scene.dt_s *= 0.5 },
];

/// What one E-6 reading leaves at the end, and how E-3's curtain compares.
#[derive(Debug, Clone)]
pub struct E6Row {
    pub reading: Reading,
    /// Largest particle speed at frames 78 (the rails stop), 100 (end of the pause), 140 (the rails
    /// stop again) and 145 (the last).
    pub speed_78: f64,
    pub speed_100: f64,
    pub speed_140: f64,
    pub speed_145: f64,
    /// Kinetic energy of both curtains at frame 145.
    pub energy_145: f64,
    /// Largest particle distance at frame 145 from the frame-25 hanging state.
    pub distance_145: f64,
    /// Largest particle speed of the E-3 curtain 5 s after release (frame 5), the time E-6 leaves
    /// between the rails' stop and its last frame.
    pub e3_speed_5: f64,
    /// The whole run.
    pub theatre: E6Theatre,
}

/// Rest as E-3 measures it (spec E-3: max speed below 0.01).
pub const AT_REST_SPEED: f64 = 0.01;

impl E6Row {
    /// Seconds the curtains would need after the rails stop at frame 140 to fall below
    /// [`AT_REST_SPEED`] if they decayed as fast as they do in the 22 s pause (frames 78–100).
    pub fn rest_time_after_140(&self) -> f64 {
        pause_rest_time(self.speed_78, self.speed_100, self.speed_140)
    }
}

/// The time to fall from `from` to [`AT_REST_SPEED`] at the exponential decay from `start` to `end`
/// over the 22 s pause.
pub fn pause_rest_time(start: f64, end: f64, from: f64) -> f64 {
    let rate = (end / start).ln() / 22.0;
    (AT_REST_SPEED / from).ln() / rate
}

/// Runs E-6 under each reading of [`E6_READINGS`].
pub fn e6_search() -> Result<Vec<E6Row>> {
    E6_READINGS.iter().map(|&reading| e6_row(reading)).collect()
}

/// E-6 under one reading.
pub fn e6_row(reading: Reading) -> Result<E6Row> {
    let t = e6_theatre_with(reading.edit)?;
    let (loaded, mut curtain) = ThesisScene::Curtain.world(reading.edit)?;
    run_to_frame(&loaded, &mut curtain, 5)?;
    Ok(E6Row {
        reading,
        speed_78: t.max_speed[77],
        speed_100: t.max_speed[99],
        speed_140: t.max_speed[139],
        speed_145: t.max_speed[144],
        energy_145: t.kinetic_energy[144],
        distance_145: t.distance_from_hanging,
        e3_speed_5: curtain.diagnostics().max_speed,
        theatre: t,
    })
}

// ---------------------------------------------------------------------------------------------- E-8

/// E-8: the tablecloth falling on the table.
#[derive(Debug, Clone)]
pub struct E8Tablecloth {
    /// First time (s) a particle's path met the table.
    pub first_contact_time: Option<f64>,
    /// Particles inside the table, summed over every step.
    pub penetrations_total: usize,
    /// Height of the centre particle at the end (table top at y = 10).
    pub centre_y: f64,
    /// Mean height of the four corner particles at the end.
    pub corner_y: f64,
    pub max_speed_last: f64,
    pub collisions_with_objects: u64,
}

/// Runs E-8, checking for particles inside the table after every step.
pub fn e8_tablecloth(friction: FrictionMode) -> Result<E8Tablecloth> {
    let (loaded, mut world) = ThesisScene::Tablecloth.world(|l| l.scene.friction.mode = friction)?;
    let info = world.surfaces()[0].clone();
    let mut first_contact_time = None;
    let mut penetrations_total = 0;
    for _ in 0..loaded.scene.n_steps() {
        world.step()?;
        if first_contact_time.is_none() && world.collision_counts().with_objects > 0 {
            first_contact_time = Some(world.time());
        }
        penetrations_total += world.penetrations();
    }
    let x = world.surface_positions(0);
    let (m, n) = (info.rows, info.cols);
    let centre = (x[info.grid.index(m / 2 - 1, n / 2 - 1)].y
        + x[info.grid.index(m / 2, n / 2)].y
        + x[info.grid.index(m / 2 - 1, n / 2)].y
        + x[info.grid.index(m / 2, n / 2 - 1)].y)
        / 4.0;
    let corners = [
        info.grid.index(0, 0),
        info.grid.index(0, n - 1),
        info.grid.index(m - 1, 0),
        info.grid.index(m - 1, n - 1),
    ];
    Ok(E8Tablecloth {
        first_contact_time,
        penetrations_total,
        centre_y: centre,
        corner_y: corners.iter().map(|&p| x[p].y).sum::<f64>() / 4.0,
        max_speed_last: world.diagnostics().max_speed,
        collisions_with_objects: world.collision_counts().with_objects,
    })
}
