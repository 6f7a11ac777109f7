//! Loading a scene file of any kind, once, with every part it names.

use std::fs;
use std::path::{Path, PathBuf};

use anima_body::{BodyScene, BuiltinSkeleton, Skeleton, SkeletonSource};
use anima_cloth::flex3d::FLEX3D_GRAVITY;
use anima_cloth::oliveira::{BuildError, OliveiraScene, ShapeDesc};
use anima_control::Controller;
use anima_format::ron_text::struct_name;
use anima_format::{FieldError, utf8};
use anima_geom::obt::{IndexBase, read_obt};
use anima_geom::{DVec3, TriangleMesh, read_obj};
use anima_ode::Integrator;

use crate::body::LoadedBody;
use crate::character::{CharacterScene, LoadedCharacter};
use crate::flex3d::LoadedFlex3d;
use crate::oliveira::LoadedOliveira;
use crate::optimisation::ObjectiveSpec;
use crate::optimisation::{LoadedOptimisation, OptimisationSpec};
use crate::sheet::SheetScene;
use crate::{SceneError, par};

/// Choices the caller makes over the file.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct LoadOptions {
    /// Gravity for a FLEX3D run, m/s². When given it replaces whatever the file says (a `.PAR` script's
    /// `GRAVIDADE`, a RON scene's `gravity_m_s2`): spec S3.1 lets the command line override the keyword.
    /// When `None`, a `.PAR` script without `GRAVIDADE` gets [`FLEX3D_GRAVITY`], "on" (spec S3.1).
    pub gravity: Option<DVec3>,
}

/// The kinds of scene file anima reads.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SceneKind {
    /// A FLEX3D surface scene: a `.PAR` script or `Flex3dScene(…)`.
    Flex3d,
    /// A spring-network sheet, `SheetScene(…)` (the standard benchmark sheets).
    Sheet,
    /// An Oliveira 2013 drape, `OliveiraScene(…)` or, remeshed, `AdaptiveOliveiraScene(…)`.
    Oliveira,
    /// Articulated figures holding poses, `BodyScene(…)`.
    Body,
    /// Articulated figures driven by a controller, `CharacterScene(…)`.
    Character,
}

impl SceneKind {
    /// The kind's name as the `anima` command and its summaries print it.
    pub fn name(self) -> &'static str {
        match self {
            SceneKind::Flex3d => "FLEX3D",
            SceneKind::Sheet => "sheet",
            SceneKind::Oliveira => "Oliveira drape",
            SceneKind::Body => "body",
            SceneKind::Character => "character",
        }
    }
}

/// A scene file and every part it names, read and checked.
#[derive(Debug, Clone, PartialEq)]
#[expect(clippy::large_enum_variant, reason = "a scene is loaded once per run: its size costs nothing")]
pub enum Scene {
    Flex3d(LoadedFlex3d),
    Sheet(SheetScene),
    Oliveira(LoadedOliveira),
    Body(LoadedBody),
    Character(LoadedCharacter),
}

impl Scene {
    pub fn kind(&self) -> SceneKind {
        match self {
            Scene::Flex3d(_) => SceneKind::Flex3d,
            Scene::Sheet(_) => SceneKind::Sheet,
            Scene::Oliveira(_) => SceneKind::Oliveira,
            Scene::Body(_) => SceneKind::Body,
            Scene::Character(_) => SceneKind::Character,
        }
    }

    /// The scene's own duration, s (what `anima run` runs without `--duration`).
    pub fn duration_s(&self) -> f64 {
        match self {
            Scene::Flex3d(l) => l.scene.duration_s,
            Scene::Sheet(s) => s.duration_s,
            Scene::Oliveira(l) => l.scene.duration_s,
            Scene::Body(l) => l.scene.duration,
            Scene::Character(l) => l.scene.duration,
        }
    }

    /// The cloth's time-stepping method; `None` for figures, which Rapier steps.
    pub fn integrator(&self) -> Option<Integrator> {
        match self {
            Scene::Flex3d(l) => Some(l.scene.integrator),
            Scene::Sheet(s) => Some(s.integrator),
            Scene::Oliveira(l) => Some(l.scene.integrator),
            Scene::Body(_) | Scene::Character(_) => None,
        }
    }

    /// One line on what a run of the scene is about to do (what `anima run` prints first).
    pub fn describe(&self) -> String {
        match self {
            Scene::Flex3d(l) => format!(
                "FLEX3D, {} steps of {} s ({}), {} frames",
                l.scene.n_steps(),
                l.scene.dt_s,
                l.scene.integrator,
                l.scene.n_frames()
            ),
            Scene::Sheet(s) => format!(
                "sheet of {} particles, {} s at {} s ({})",
                s.sheet.n * s.sheet.n,
                s.duration_s,
                s.dt_s,
                s.integrator
            ),
            Scene::Oliveira(l) => format!(
                "Oliveira drape, {} s ({}, {:?}){}",
                l.scene.duration_s,
                l.scene.integrator,
                l.scene.time_step,
                l.remesher.map(|r| format!(", remeshed: {r:?}")).unwrap_or_default()
            ),
            Scene::Body(l) => format!(
                "figures `{}`: {} models, {} steps of {} s",
                l.scene.name,
                l.scene.models.len(),
                l.scene.n_steps(),
                l.scene.world.dt
            ),
            Scene::Character(l) => format!(
                "character `{}`: {} models driven by `{}`, {} steps of {} s",
                l.scene.name,
                l.scene.models.len(),
                l.controller.name(),
                l.scene.n_steps(),
                l.scene.world.dt
            ),
        }
    }

    /// The FLEX3D scene, or an error naming the kind `path` holds instead.
    pub fn into_flex3d(self, path: &Path) -> Result<LoadedFlex3d, SceneError> {
        match self {
            Scene::Flex3d(s) => Ok(s),
            other => Err(other.wrong_kind(path, SceneKind::Flex3d)),
        }
    }

    /// The Oliveira drape, or an error naming the kind `path` holds instead.
    pub fn into_oliveira(self, path: &Path) -> Result<LoadedOliveira, SceneError> {
        match self {
            Scene::Oliveira(s) => Ok(s),
            other => Err(other.wrong_kind(path, SceneKind::Oliveira)),
        }
    }

    fn wrong_kind(&self, path: &Path, wanted: SceneKind) -> SceneError {
        SceneError::Kind {
            path: path.to_owned(),
            why: format!("expected a {} scene, found a {} scene", wanted.name(), self.kind().name()),
        }
    }
}

/// Loads a FLEX3D scene (a `.PAR` script or `Flex3dScene(…)`) with its objects; any other kind is an
/// error naming the kind found.
pub fn load_flex3d(path: &Path, opts: &LoadOptions) -> Result<LoadedFlex3d, SceneError> {
    load(path, opts)?.into_flex3d(path)
}

/// Loads an Oliveira drape (static or adaptive) with its meshes; any other kind is an error.
pub fn load_oliveira(path: &Path) -> Result<LoadedOliveira, SceneError> {
    load(path, &LoadOptions::default())?.into_oliveira(path)
}

/// The struct names of the scene kinds, for messages.
const SCENE_NAMES: &str =
    "`Flex3dScene`, `SheetScene`, `OliveiraScene`, `AdaptiveOliveiraScene`, `BodyScene` or `CharacterScene`";

/// Loads a scene of any kind and every part it names (`.OBT` objects, OBJ meshes, skeletons, the
/// controller), resolved relative to the scene file's folder. The kind is told by the extension
/// (`.par`, any case) or by the struct a `.ron` file starts with; every file is read once.
pub fn load(path: &Path, opts: &LoadOptions) -> Result<Scene, SceneError> {
    let file = File { path, folder: folder_of(path) };
    let extension = path.extension().and_then(|e| e.to_str()).unwrap_or_default().to_ascii_lowercase();
    if !matches!(extension.as_str(), "par" | "ron") {
        return Err(file.kind("expected a scene file ending in .par or .ron"));
    }
    let bytes = read_limited(path)?;
    match extension.as_str() {
        "par" => {
            let script = par::parse(&bytes).map_err(|e| file.parse_error(e))?;
            let mut scene = script.to_scene(FLEX3D_GRAVITY);
            if let Some(g) = opts.gravity {
                scene.gravity_m_s2 = g;
            }
            Ok(Scene::Flex3d(LoadedFlex3d { objects: file.obt_objects(&scene.objects)?, scene }))
        }
        "ron" => {
            let text = utf8(&bytes).map_err(|e| file.parse_error(e))?;
            load_ron(&file, text, opts)
        }
        _ => unreachable!("checked above"),
    }
}

/// The bytes of `path`, at most [`crate::limits::MAX_FILE_BYTES`] of them: a larger file (or an endless
/// one, a device) is an error before it is read whole. What every scene, part and side input (a
/// reference OBJ, a `.PAR` to convert) is read through.
pub fn read_limited(path: &Path) -> Result<Vec<u8>, SceneError> {
    use std::io::Read as _;
    let max = crate::limits::MAX_FILE_BYTES;
    let mut bytes = Vec::new();
    fs::File::open(path)
        .and_then(|f| f.take(max + 1).read_to_end(&mut bytes))
        .map_err(SceneError::read(path))?;
    if bytes.len() as u64 > max {
        return Err(SceneError::Kind {
            path: path.to_owned(),
            why: format!("expected a file of at most {} MiB", max >> 20),
        });
    }
    Ok(bytes)
}

fn load_ron(file: &File, text: &str, opts: &LoadOptions) -> Result<Scene, SceneError> {
    let parse = |e| file.parse_error(e);
    match struct_name(text).or_else(|| kind_by_fields(text)) {
        Some("Flex3dScene") => {
            let mut scene = crate::flex3d::from_ron_str(text).map_err(parse)?;
            crate::flex3d::check(&scene).map_err(|e| file.description(e.locate(text)))?;
            if let Some(g) = opts.gravity {
                scene.gravity_m_s2 = g;
            }
            Ok(Scene::Flex3d(LoadedFlex3d { objects: file.obt_objects(&scene.objects)?, scene }))
        }
        Some("SheetScene") => {
            let scene = crate::sheet::from_ron_str(text).map_err(parse)?;
            scene.check().map_err(|e| file.description(e.locate(text)))?;
            Ok(Scene::Sheet(scene))
        }
        Some("OliveiraScene") => {
            let scene = crate::oliveira::from_ron_str(text).map_err(parse)?;
            let loaded = LoadedOliveira { meshes: file.obj_meshes(&scene)?, scene, remesher: None };
            file.check_drape(text, "", &loaded)?;
            Ok(Scene::Oliveira(loaded))
        }
        Some("AdaptiveOliveiraScene") => {
            let a = crate::oliveira::adaptive_from_ron_str(text).map_err(parse)?;
            a.remesher.method().map_err(|why| file.invalid_at(text, "remesher", why))?;
            // A sizing field refines down to its shortest edge: a triangle mesh of edges e over the
            // cloth's area A has about 1.2·A/e² vertices, held to anima's particle limit here (with a
            // margin) rather than met as an allocation that aborts.
            if let crate::oliveira::Remesher::SizingField { min_edge_m, .. } = a.remesher {
                let size = a.drape.cloth.size_m;
                let shortest = size * (2.0 / crate::limits::MAX_PARTICLES as f64).sqrt();
                if min_edge_m < shortest {
                    let why = format!(
                        "expected a shortest edge of at least {shortest:.3e} m for a {size} m cloth (its finest \
                         mesh would pass anima's {} particles), found {min_edge_m:e}",
                        crate::limits::MAX_PARTICLES
                    );
                    return Err(file.invalid_at(text, "remesher.min_edge_m", why));
                }
            }
            let loaded = LoadedOliveira {
                meshes: file.obj_meshes(&a.drape)?,
                scene: a.drape,
                remesher: Some(a.remesher),
            };
            file.check_drape(text, "drape.", &loaded)?;
            Ok(Scene::Oliveira(loaded))
        }
        Some("BodyScene") => {
            let scene = BodyScene::from_ron_str(text).map_err(|e| file.description(e))?;
            let interval = scene.frame_interval_s().map_err(|e| file.description(e))?;
            if let Some(why) = figures_run_problem(scene.duration, scene.world.dt, interval) {
                return Err(file.invalid_at(text, "duration_s", why));
            }
            let skeletons =
                scene.models.iter().map(|m| file.skeleton(&m.skeleton)).collect::<Result<Vec<_>, _>>()?;
            Ok(Scene::Body(LoadedBody { scene, skeletons }))
        }
        Some("CharacterScene") => Ok(Scene::Character(file.character(text)?)),
        Some("Optimisation") => {
            Err(file.kind("an optimisation spec, not a scene: run it with `anima optimise`"))
        }
        Some("Skeleton") => {
            Err(file
                .kind("a skeleton, which is a part of a scene: name it in a `BodyScene` or `CharacterScene`"))
        }
        Some("Controller") => Err(file.kind(
            "a controller, which is a part of a scene: name it in a `CharacterScene` or an `Optimisation`",
        )),
        Some(other) => Err(file.kind(&format!("expected a scene ({SCENE_NAMES}), found `{other}`"))),
        None => Err(file.kind(&format!(
            "cannot tell which kind of scene this is: start it with its kind, one of {SCENE_NAMES}"
        ))),
    }
}

/// The kind of an unnamed RON scene, from a top-level field only one kind has.
fn kind_by_fields(text: &str) -> Option<&'static str> {
    let sites = anima_format::ron_path::field_sites(text);
    let top = |name: &str| sites.iter().any(|s| s.path == name);
    if top("surfaces") {
        Some("Flex3dScene")
    } else if top("cloth") && top("material") {
        Some("OliveiraScene")
    } else if top("drape") && top("remesher") {
        Some("AdaptiveOliveiraScene")
    } else if top("sheet") {
        Some("SheetScene")
    } else if top("controller") && top("models") {
        Some("CharacterScene")
    } else if top("models") {
        Some("BodyScene")
    } else {
        None
    }
}

/// Loads an optimisation spec and the controller it names.
pub fn load_optimisation(path: &Path) -> Result<LoadedOptimisation, SceneError> {
    let bytes = read_limited(path)?;
    let file = File { path, folder: folder_of(path) };
    let text = utf8(&bytes).map_err(|e| file.parse_error(e))?;
    match struct_name(text) {
        Some("Optimisation") | None => {}
        Some(other) => {
            return Err(
                file.kind(&format!("expected an optimisation spec, `Optimisation(…)`, found `{other}`"))
            );
        }
    }
    let spec: OptimisationSpec = anima_format::ron_text::from_str(text).map_err(|e| file.parse_error(e))?;
    if spec.evaluations == 0 {
        return Err(file.invalid_at(text, "evaluations", "expected at least one evaluation".into()));
    }
    if let Some((field, why)) = spec.count_problem() {
        return Err(file.invalid_at(text, &field, why));
    }
    // The name becomes two file names in the output folder: a path would write (and, with `--fresh`,
    // delete) files elsewhere.
    if let Some(why) = anima_format::not_a_plain_name(&spec.name) {
        return Err(file.invalid_at(text, "name", format!("expected {why}, found {:?}", spec.name)));
    }
    let (controller, path, controller_text) = file.controller(&spec.controller)?;
    // The objective's figure is a built-in skeleton: the controller's actuators, sensors and procedures
    // are checked against it here, at their lines, rather than at the first evaluation.
    let skeleton = match spec.objective {
        ObjectiveSpec::Walk { .. } => BuiltinSkeleton::Humanoid,
        ObjectiveSpec::Throw { .. } => BuiltinSkeleton::Thrower,
    }
    .load();
    if let ObjectiveSpec::Walk { actuation: Some(a), .. } = spec.objective {
        skeleton.clone().with_actuation(a).map_err(|e| {
            file.description(
                FieldError::invalid(format!("objective.actuation.{}", e.field), e.message).locate(text),
            )
        })?;
    }
    anima_character::check_controller(&controller, &[&skeleton], &anima_character::procedures(), &[])
        .map_err(|e| file.controller_error(&e, text, path, &controller_text))?;
    Ok(LoadedOptimisation { spec, controller })
}

fn folder_of(path: &Path) -> &Path {
    match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    }
}

/// The scene file being loaded, for its parts and its errors.
struct File<'a> {
    path: &'a Path,
    folder: &'a Path,
}

impl File<'_> {
    fn parse_error(&self, e: anima_format::ParseError) -> SceneError {
        SceneError::Parse(e.with_file(self.path.display().to_string()))
    }

    fn description(&self, e: FieldError) -> SceneError {
        SceneError::Description { path: self.path.to_owned(), source: e }
    }

    fn kind(&self, why: &str) -> SceneError {
        SceneError::Kind { path: self.path.to_owned(), why: why.to_owned() }
    }

    /// A value of field `field` the format accepts but a run cannot use, placed at its line.
    fn invalid_at(&self, text: &str, field: &str, why: String) -> SceneError {
        self.description(FieldError::invalid(field, why).locate(text))
    }

    fn read(&self, what: &'static str, name: &str) -> Result<(PathBuf, Vec<u8>), SceneError> {
        let path = self.folder.join(name);
        if !path.is_file() {
            return Err(SceneError::PartNotFound {
                scene: self.path.to_owned(),
                what,
                name: name.to_owned(),
                folder: self.folder.to_owned(),
            });
        }
        let bytes = read_limited(&path)?;
        Ok((path, bytes))
    }

    /// FLEX3D's `.OBT` objects: the exact name first, then a case-insensitive match in the same folder
    /// (spec S2.5: A2.8 writes `mesa.obt` while the format's extension is `.OBT`).
    fn obt_objects(&self, names: &[String]) -> Result<Vec<(String, TriangleMesh)>, SceneError> {
        names
            .iter()
            .map(|name| {
                let path = resolve(self.folder, name).ok_or_else(|| SceneError::PartNotFound {
                    scene: self.path.to_owned(),
                    what: "object file (tried the exact name, then ignoring case)",
                    name: name.clone(),
                    folder: self.folder.to_owned(),
                })?;
                let bytes = read_limited(&path)?;
                let object = read_obt(&bytes[..], IndexBase::Auto)
                    .map_err(|source| SceneError::Obt { path: path.clone(), source })?;
                let mesh = object.to_mesh().map_err(|source| SceneError::Mesh { path, source })?;
                Ok((name.clone(), mesh))
            })
            .collect()
    }

    /// The OBJ meshes of a drape's `Mesh` objects, in scene order.
    fn obj_meshes(&self, scene: &OliveiraScene) -> Result<Vec<(String, TriangleMesh)>, SceneError> {
        let mut meshes = Vec::new();
        for object in &scene.objects {
            if let ShapeDesc::Mesh { file, .. } = &object.shape {
                let (path, bytes) = self.read("mesh file", file)?;
                let mesh = read_obj(&bytes[..]).map_err(|source| SceneError::Obj { path, source })?;
                meshes.push((file.clone(), mesh));
            }
        }
        Ok(meshes)
    }

    /// A drape is checked by building it (the cloth crate checks every value and names the field); the
    /// field is then placed at its line. `prefix` is where the drape sits in the file (`drape.` in an
    /// adaptive scene).
    fn check_drape(&self, text: &str, prefix: &str, loaded: &LoadedOliveira) -> Result<(), SceneError> {
        let scene = &loaded.scene;
        if !(scene.duration_s > 0.0 && scene.duration_s.is_finite()) {
            let why = format!("expected a positive number of seconds, found {}", scene.duration_s);
            return Err(self.invalid_at(text, &format!("{prefix}duration_s"), why));
        }
        if let Err(why) = crate::oliveira::check_contact(scene) {
            return Err(self.invalid_at(text, &format!("{prefix}options.contact"), why));
        }
        let n = scene.cloth.vertices_per_side;
        let max_side = crate::limits::MAX_PARTICLES.isqrt();
        if n > max_side {
            let why = format!("expected at most {max_side} vertices a side, found {n}");
            return Err(self.invalid_at(text, &format!("{prefix}cloth.vertices_per_side"), why));
        }
        let e = match loaded.build() {
            Ok(cloth) => {
                let dt = loaded.step_estimate(&cloth);
                return match crate::limits::run_length_problem(scene.duration_s, dt, None) {
                    Some(why) => {
                        Err(self.invalid_at(text, &format!("{prefix}time_step"), format!("expected {why}")))
                    }
                    None => Ok(()),
                };
            }
            Err(e) => e,
        };
        let sites = anima_format::ron_path::field_sites(text);
        let field = match &e {
            // The material names its bad field in the message: `field `young_modulus_pa` is out of range`.
            BuildError::Field { field: "material", message } if message.contains("field `") => {
                let name = message.split('`').nth(1).unwrap_or_default();
                format!("{prefix}material.{name}")
            }
            BuildError::Field { field, .. } => sites
                .iter()
                .map(|s| s.path.as_str())
                .find(|p| {
                    p.starts_with(prefix)
                        && (*p == format!("{prefix}{field}") || p.ends_with(&format!(".{field}")))
                })
                .map_or(format!("{prefix}{field}"), str::to_owned),
            BuildError::Object { name, .. } => scene
                .objects
                .iter()
                .position(|o| &o.name == name)
                .map_or(format!("{prefix}objects"), |k| format!("{prefix}objects[{k}]")),
            _ => format!("{prefix}cloth"),
        };
        Err(self.description(FieldError::invalid(field, e.to_string()).locate(text)))
    }

    fn skeleton(&self, source: &SkeletonSource) -> Result<Skeleton, SceneError> {
        match source {
            SkeletonSource::Builtin(b) => Ok(b.load()),
            SkeletonSource::File(f) => {
                let (path, bytes) = self.read("skeleton file", f)?;
                let text =
                    utf8(&bytes).map_err(|e| SceneError::Parse(e.with_file(path.display().to_string())))?;
                Skeleton::from_ron_str(text).map_err(|source| SceneError::Description { path, source })
            }
        }
    }

    /// A controller that does not bind to its figures: at its line of the controller file (at `path`,
    /// holding `controller_text`) when the error names one of its fields, else at this file's
    /// `controller` field.
    fn controller_error(
        &self,
        e: &anima_character::CharacterError,
        text: &str,
        path: PathBuf,
        controller_text: &str,
    ) -> SceneError {
        match e.field_error(controller_text) {
            Some(source) => SceneError::Description { path, source },
            None => self.invalid_at(text, "controller", e.to_string()),
        }
    }

    /// The controller file `name`, read with the character procedures, with its path and text.
    fn controller(&self, name: &str) -> Result<(Controller, PathBuf, String), SceneError> {
        let (path, bytes) = self.read("controller file", name)?;
        let text = utf8(&bytes).map_err(|e| SceneError::Parse(e.with_file(path.display().to_string())))?;
        match Controller::from_ron(text, &anima_character::procedures()) {
            Ok(c) => Ok((c, path, text.to_owned())),
            Err(source) => Err(SceneError::Description { path, source }),
        }
    }

    fn character(&self, text: &str) -> Result<LoadedCharacter, SceneError> {
        let scene: CharacterScene =
            anima_format::ron_text::from_str(text).map_err(|e| self.parse_error(e))?;
        check_positive(self, text, "duration_s", scene.duration)?;
        let interval = anima_body::scene::frame_interval_of(scene.frame_rate_hz, scene.frame_interval)
            .map_err(|(field, why)| self.invalid_at(text, field, why))?;
        check_positive(self, text, "world.dt_s", scene.world.dt)?;
        scene.world.check().map_err(|e| self.invalid_at(text, "world", e.to_string()))?;
        if let Some(why) = figures_run_problem(scene.duration, scene.world.dt, interval) {
            return Err(self.invalid_at(text, "duration_s", why));
        }
        if scene.models.is_empty() {
            return Err(self.invalid_at(text, "models", "expected at least one model".into()));
        }
        let mut skeletons = Vec::with_capacity(scene.models.len());
        for (k, m) in scene.models.iter().enumerate() {
            let sk = self.skeleton(&m.skeleton)?;
            let sk = match &m.actuation {
                Some(a) => sk.with_actuation(*a).map_err(|e| {
                    self.description(
                        FieldError::invalid(format!("models[{k}].{}", e.field), e.message).locate(text),
                    )
                })?,
                None => sk,
            };
            skeletons.push(sk);
        }
        let (controller, controller_path, controller_text) = self.controller(&scene.controller)?;
        // The controller bound to the models without a world: every actuator one of theirs (`alias/name`,
        // or a model's own name when there is one model), every sensor's kind and arguments, every
        // procedure's bodies; a wrong one is an error before the run, at its line of the controller file
        // where it has one.
        let skeleton_refs: Vec<&Skeleton> = skeletons.iter().collect();
        let aliases: Vec<&str> = scene.models.iter().map(|m| m.alias.as_str()).collect();
        anima_character::check_controller(
            &controller,
            &skeleton_refs,
            &anima_character::procedures(),
            &aliases,
        )
        .map_err(|e| match e {
            anima_character::CharacterError::Actuator(name) => self.invalid_at(
                text,
                "controller",
                format!("controller actuator `{name}` names no actuator of the scene's models"),
            ),
            e => self.controller_error(&e, text, controller_path, &controller_text),
        })?;
        Ok(LoadedCharacter { scene, skeletons, controller })
    }
}

/// Why a run of figures of `duration` s at control steps of `dt` s, a picture every `frame_interval` s,
/// cannot be run ([`crate::limits`]), or `None`.
pub fn figures_run_problem(duration: f64, dt: f64, frame_interval: f64) -> Option<String> {
    crate::limits::run_length_problem(duration, dt, Some(1.0 / frame_interval.max(dt)))
        .map(|why| format!("expected {why}"))
}

fn check_positive(file: &File, text: &str, field: &str, v: f64) -> Result<(), SceneError> {
    if v > 0.0 && v.is_finite() {
        Ok(())
    } else {
        Err(file.invalid_at(text, field, format!("expected a positive number of seconds, found {v}")))
    }
}

/// The exact name first, then a case-insensitive match in the same folder. Several case-insensitive
/// matches: the first in byte order, so the choice does not depend on the file system's listing order.
fn resolve(folder: &Path, name: &str) -> Option<PathBuf> {
    let exact = folder.join(name);
    if exact.is_file() {
        return Some(exact);
    }
    let wanted = exact.file_name()?.to_str()?.to_lowercase();
    let mut found: Vec<PathBuf> = fs::read_dir(exact.parent()?)
        .ok()?
        .filter_map(Result::ok)
        .filter(|e| e.file_name().to_str().is_some_and(|n| n.to_lowercase() == wanted))
        .map(|e| e.path())
        .filter(|p| p.is_file())
        .collect();
    found.sort();
    found.into_iter().next()
}
