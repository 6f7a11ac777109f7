//! What a run needs from each kind of scene, behind one trait: the one place the runtime tells the
//! kinds apart is [`each_kind`], and everything else (the stale-output sweep, the run itself, the
//! command line's changes and the check after them) asks the kind through [`KindRun`]. A new kind of
//! scene is one `impl KindRun` and one arm there, not an arm in every function that looks at a scene.

use anima_cloth::oliveira::StepRule;
use anima_scene::Scene;
use anima_scene::body::LoadedBody;
use anima_scene::character::LoadedCharacter;
use anima_scene::flex3d::LoadedFlex3d;
use anima_scene::oliveira::LoadedOliveira;
use anima_scene::sheet::SheetScene;
use anyhow::Result;

use anima_cloth::flex3d::Flex3dWorld;
use anyhow::Context;

use super::body::{Posed, build_character};
use super::{Overrides, Progress, RunOptions, Summary, body, figures_problem, flex3d, oliveira, sheet};
use crate::drape::object_meshes;
use crate::output::is_frame_file;
use crate::sim::{ClothParts, FigureModel};

/// Binds `$k` to the scene's loaded kind (by reference or by mutable reference, as `$scene` is) and
/// evaluates `$body` with it: the runtime's one match on the scene's kind.
macro_rules! each_kind {
    ($scene:expr, $k:ident => $body:expr) => {
        match $scene {
            Scene::Flex3d($k) => $body,
            Scene::Sheet($k) => $body,
            Scene::Oliveira($k) => $body,
            Scene::Body($k) => $body,
            Scene::Character($k) => $body,
        }
    };
}

/// The scene's kind, to ask.
pub(crate) fn kind(scene: &Scene) -> &dyn KindRun {
    each_kind!(scene, k => k)
}

/// The scene's kind, to change.
pub(crate) fn kind_mut(scene: &mut Scene) -> &mut dyn KindRun {
    each_kind!(scene, k => k)
}

/// The command line's changes as one kind applies them: the times already checked positive.
pub(crate) struct Changes<'a> {
    pub overrides: &'a Overrides,
    pub dt: Option<f64>,
    pub duration: Option<f64>,
    /// The kind's name, for the error that a change does not apply to it.
    pub kind: &'static str,
}

impl Changes<'_> {
    fn not_for(&self, what: &str) -> anyhow::Error {
        anyhow::anyhow!("{what} does not apply to a {} scene", self.kind)
    }

    /// The FLEX3D reconstructions apply to FLEX3D scenes alone.
    fn refuse_flex3d_switches(&self) -> Result<()> {
        if self.overrides.flex3d.any() {
            return Err(self.not_for("a FLEX3D switch (--friction, --contact, --static-response, …)"));
        }
        Ok(())
    }

    /// A cloth that steps at a fixed Δt takes no adaptive integrator.
    fn check_fixed_step_integrator(&self) -> Result<()> {
        if let Some(i) = self.overrides.integrator {
            anima_cloth::check_fixed_step_integrator(i)
                .map_err(|why| anyhow::anyhow!("--integrator {i}: {why}"))?;
        }
        Ok(())
    }

    /// A figures scene's world sets everything but its step and its length.
    fn apply_to_figures(&self, world_dt: &mut f64, scene_duration: &mut f64) -> Result<()> {
        self.refuse_flex3d_switches()?;
        let o = self.overrides;
        if o.integrator.is_some()
            || o.gravity.is_some()
            || o.contact_mode.is_some()
            || o.self_collision.is_some()
        {
            return Err(self.not_for(
                "--integrator, --gravity, --contact-mode or --self-collision (a figure's world sets them)",
            ));
        }
        set(world_dt, self.dt);
        set(scene_duration, self.duration);
        Ok(())
    }
}

/// Replaces `field` with the value given, if one was.
fn set<T>(field: &mut T, value: Option<T>) {
    if let Some(v) = value {
        *field = v;
    }
}

/// What running a scene asks of its kind.
pub(crate) trait KindRun {
    /// Whether `name`, a file in the output folder, is a frame a run of this kind writes.
    fn is_frame_file(&self, name: &str) -> bool;
    /// Runs the scene to its end, writing what `opts` asks for.
    fn run(&self, label: &str, opts: &RunOptions, progress: &mut dyn Progress) -> Result<Summary>;
    /// Applies the command line's changes, or says which one does not apply to this kind.
    fn apply(&mut self, changes: &Changes<'_>) -> Result<()>;
    /// What keeps the scene, as it now is, from running (`anima_scene::limits`), if anything.
    fn problem(&self) -> Option<String>;
    /// Whether a run of this kind compares its end with reference positions ([`super::RunOptions::reference`]).
    fn takes_reference(&self) -> bool {
        false
    }
    /// The scene as a cloth to step ([`crate::sim::ClothSim`]); `None` for figures.
    fn cloth(&self) -> Option<Result<ClothParts>> {
        None
    }
    /// The scene as figures to step ([`crate::sim::FigureSim`]); `None` for cloth.
    fn figures(&self) -> Option<Result<FigureModel>> {
        None
    }
}

impl KindRun for LoadedFlex3d {
    fn is_frame_file(&self, name: &str) -> bool {
        self.scene.surfaces.iter().any(|s| {
            let prefix = format!("{}_", s.name);
            is_frame_file(name, &prefix, ".OBT") || is_frame_file(name, &prefix, ".obj")
        })
    }

    fn run(&self, label: &str, opts: &RunOptions, progress: &mut dyn Progress) -> Result<Summary> {
        Ok(flex3d::run(self, label, opts, progress)?.0)
    }

    fn apply(&mut self, changes: &Changes<'_>) -> Result<()> {
        changes.check_fixed_step_integrator()?;
        let (o, s) = (changes.overrides, &mut self.scene);
        set(&mut s.integrator, o.integrator);
        set(&mut s.dt_s, changes.dt);
        set(&mut s.duration_s, changes.duration);
        set(&mut s.gravity_m_s2, o.gravity);
        set(&mut s.options.object_contact, o.contact_mode);
        set(&mut s.options.self_collision, o.self_collision);
        let f = &o.flex3d;
        set(&mut s.friction.mode, f.friction);
        set(&mut s.options.contact, f.contact);
        set(&mut s.options.static_response, f.static_response);
        s.options.external_force_is_acceleration |= f.external_is_acceleration;
        s.options.bend_reaction |= f.bend_reaction;
        s.options.friction_clamp |= f.friction_clamp;
        if f.no_collisions {
            s.options.collisions = false;
        }
        Ok(())
    }

    fn problem(&self) -> Option<String> {
        anima_scene::flex3d::check(&self.scene).err().map(|e| e.to_string())
    }

    fn cloth(&self) -> Option<Result<ClothParts>> {
        Some(Flex3dWorld::new(&self.scene, self.meshes()).context("building the scene").map(|world| {
            let (triangles, obstacles) = (world.all_triangles(), world.objects().to_vec());
            ClothParts { model: Box::new(world), triangles, obstacles, kind: "flex3d" }
        }))
    }
}

impl KindRun for SheetScene {
    fn is_frame_file(&self, name: &str) -> bool {
        is_frame_file(name, "sheet_", ".obj")
    }

    fn takes_reference(&self) -> bool {
        true
    }

    fn run(&self, label: &str, opts: &RunOptions, progress: &mut dyn Progress) -> Result<Summary> {
        sheet::run(self, label, opts, progress)
    }

    fn apply(&mut self, changes: &Changes<'_>) -> Result<()> {
        changes.refuse_flex3d_switches()?;
        let o = changes.overrides;
        if o.contact_mode.is_some() {
            return Err(changes.not_for("--contact-mode (the standard sheets touch no object)"));
        }
        if o.self_collision.is_some() {
            return Err(changes.not_for("--self-collision (a hanging standard sheet never folds)"));
        }
        if o.gravity.is_some() {
            return Err(changes.not_for("--gravity (the standard sheet's gravity is part of its definition)"));
        }
        set(&mut self.integrator, o.integrator);
        set(&mut self.dt_s, changes.dt);
        set(&mut self.duration_s, changes.duration);
        Ok(())
    }

    fn problem(&self) -> Option<String> {
        self.check().err().map(|e| e.to_string())
    }

    fn cloth(&self) -> Option<Result<ClothParts>> {
        Some(sheet::new_cloth(self, false).map(|(model, triangles)| ClothParts {
            model,
            triangles,
            obstacles: Vec::new(),
            kind: "sheet",
        }))
    }
}

impl KindRun for LoadedOliveira {
    fn is_frame_file(&self, name: &str) -> bool {
        is_frame_file(name, "cloth_", ".obj")
    }

    fn run(&self, label: &str, opts: &RunOptions, progress: &mut dyn Progress) -> Result<Summary> {
        oliveira::run(self, label, opts, progress)
    }

    fn apply(&mut self, changes: &Changes<'_>) -> Result<()> {
        changes.refuse_flex3d_switches()?;
        changes.check_fixed_step_integrator()?;
        let (o, s) = (changes.overrides, &mut self.scene);
        set(&mut s.integrator, o.integrator);
        set(&mut s.time_step, changes.dt.map(|dt_s| StepRule::Fixed { dt_s }));
        set(&mut s.duration_s, changes.duration);
        set(&mut s.gravity_m_s2, o.gravity);
        set(&mut s.options.contact, o.contact_mode);
        set(&mut s.options.self_collision, o.self_collision);
        Ok(())
    }

    fn problem(&self) -> Option<String> {
        anima_scene::oliveira::check_contact(&self.scene).err()
    }

    fn cloth(&self) -> Option<Result<ClothParts>> {
        Some(self.build().context("building the drape").map(|cloth| {
            let obstacles = object_meshes(&cloth).into_iter().map(|(m, _)| m).collect();
            ClothParts {
                model: Box::new(self.with_remesher(cloth)),
                triangles: Vec::new(),
                obstacles,
                kind: "oliveira",
            }
        }))
    }
}

impl KindRun for LoadedBody {
    fn is_frame_file(&self, name: &str) -> bool {
        is_frame_file(name, "frame_", ".png")
    }

    fn run(&self, label: &str, opts: &RunOptions, progress: &mut dyn Progress) -> Result<Summary> {
        body::run_body(self, label, opts, progress)
    }

    fn figures(&self) -> Option<Result<FigureModel>> {
        Some(Posed::build(self).map(|p| FigureModel::Posed(Box::new(p))))
    }

    fn apply(&mut self, changes: &Changes<'_>) -> Result<()> {
        changes.apply_to_figures(&mut self.scene.world.dt, &mut self.scene.duration)
    }

    fn problem(&self) -> Option<String> {
        figures_problem(self.scene.duration, self.scene.world.dt, self.scene.frame_interval_s())
    }
}

impl KindRun for LoadedCharacter {
    fn is_frame_file(&self, name: &str) -> bool {
        is_frame_file(name, "frame_", ".png")
    }

    fn run(&self, label: &str, opts: &RunOptions, progress: &mut dyn Progress) -> Result<Summary> {
        body::run_character(self, label, opts, progress)
    }

    fn figures(&self) -> Option<Result<FigureModel>> {
        Some(build_character(self).map(|c| FigureModel::Character(Box::new(c))))
    }

    fn apply(&mut self, changes: &Changes<'_>) -> Result<()> {
        changes.apply_to_figures(&mut self.scene.world.dt, &mut self.scene.duration)
    }

    fn problem(&self) -> Option<String> {
        figures_problem(self.scene.duration, self.scene.world.dt, self.scene.frame_interval_s())
    }
}
