//! Hostile but fair input to `anima`: every case gets a located error and exit status 1, no panic,
//! nothing written outside `--out`, nothing unbounded. One test per category of the hostile-input issue.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

mod common;

use common::{anima, temp_dir};

fn assets(rel: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets").join(rel)
}

/// `assets/<rel>` with `from` replaced by `to`, written into `dir` as `name`.
fn edited(dir: &Path, rel: &str, from: &str, to: &str, name: &str) -> PathBuf {
    let text = std::fs::read_to_string(assets(rel)).unwrap();
    assert!(text.contains(from), "{rel} has `{from}`");
    let p = dir.join(name);
    std::fs::write(&p, text.replace(from, to)).unwrap();
    p
}

fn run(dir: &Path, scene: &Path, extra: &[&str]) -> Output {
    anima()
        .args(["run", "--quiet", "--no-pictures", "--out"])
        .arg(dir.join("out"))
        .args(extra)
        .arg(scene)
        .output()
        .unwrap()
}

/// The run was refused with exit status 1 and an error that contains each of `wanted`.
fn refused(o: &Output, wanted: &[&str]) -> String {
    let err = String::from_utf8_lossy(&o.stderr).into_owned();
    assert_eq!(o.status.code(), Some(1), "exit status 1 for bad input: {err}");
    assert!(!err.contains("panicked"), "{err}");
    for w in wanted {
        assert!(err.contains(w), "the error says `{w}`: {err}");
    }
    err
}

/// Every file under `dir`, recursively.
fn all_files(dir: &Path) -> Vec<PathBuf> {
    let mut out = Vec::new();
    if let Ok(entries) = std::fs::read_dir(dir) {
        for e in entries {
            let p = e.unwrap().path();
            if p.is_dir() { out.extend(all_files(&p)) } else { out.push(p) }
        }
    }
    out
}

#[test]
fn output_names_are_data_not_paths() {
    let dir = temp_dir("names");
    let escape =
        edited(&dir, "flex3d/a2-2-vento.par", "SUPERFÍCIE\n", "SUPERFÍCIE ../../escaped\n", "escape.par");
    refused(&run(&dir, &escape, &[]), &["escape.par:8:12:", "../../escaped", "does not start with `.`"]);
    let ron =
        edited(&dir, "flex3d/wind.ron", "name: \"SUPERFICIE1\"", "name: \"/tmp/escaped\"", "escape.ron");
    refused(&run(&dir, &ron, &[]), &["escape.ron", "surfaces[0].name", "line"]);
    // Two surfaces of one name would write over each other's frames.
    let twice = edited(&dir, "flex3d/a2-4-cortinas.par", "SUPERFÍCIE cortd", "SUPERFÍCIE corte", "twice.par");
    refused(
        &run(&dir, &twice, &[]),
        &["twice.par:", "a name no other surface has (surface 1 is `corte` too)"],
    );
    assert!(!dir.parent().unwrap().join("escaped").exists() && !Path::new("/tmp/escaped_1.OBT").exists());
    assert!(all_files(&dir.join("out")).is_empty(), "nothing written for a refused scene");
    // `convert` never writes over its input, and asks before writing over anything else.
    let par = dir.join("vento.par");
    std::fs::copy(assets("flex3d/a2-2-vento.par"), &par).unwrap();
    let o = anima().args(["convert", "-o"]).arg(&par).arg(&par).output().unwrap();
    refused(&o, &["would overwrite the input"]);
    assert_eq!(std::fs::read(&par).unwrap(), std::fs::read(assets("flex3d/a2-2-vento.par")).unwrap());
    let ron = dir.join("vento.ron");
    std::fs::write(&ron, "keep me").unwrap();
    refused(&anima().arg("convert").arg(&par).output().unwrap(), &["exists; pass --force"]);
    assert_eq!(std::fs::read_to_string(&ron).unwrap(), "keep me");
    assert!(anima().args(["convert", "--force"]).arg(&par).status().unwrap().success());
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn declared_sizes_and_counts_are_bounded_before_anything_is_allocated() {
    let dir = temp_dir("limits");
    for (from, to, wanted) in [
        ("MALHA (10 10)", "MALHA (100000 100000)", "number at most 4000000"),
        ("MALHA (10 10)", "MALHA (4294967296 4294967296)", "number at most 4000000"),
        ("PONTOS_FIXOS = 3", "PONTOS_FIXOS = 1000000000", "at most 100 fixed points"),
        ("DELTA_t = 0.001", "DELTA_t = 1e-300", "a run of at most 1e9 steps"),
        ("DURAÇÃO = 4", "DURAÇÃO = 1e308", "a run of at most 1e9 steps"),
        ("QUADROS_SEG = 5", "QUADROS_SEG = 100000", "at most one frame per step"),
    ] {
        let p = edited(&dir, "flex3d/a2-2-vento.par", from, to, "big.par");
        let err = refused(&run(&dir, &p, &[]), &["big.par:", wanted]);
        // Located: file:line:column.
        assert!(
            err.split("big.par:").nth(1).is_some_and(|r| r.chars().next().unwrap().is_ascii_digit()),
            "{err}"
        );
    }
    // `NUM_SUPERFÍCIES = 1e11` is no whole number; a huge whole one only runs out of surfaces to read.
    let p = edited(
        &dir,
        "flex3d/a2-2-vento.par",
        "NUM_SUPERFÍCIES = 1",
        "NUM_SUPERFÍCIES = 100000000000",
        "many.par",
    );
    refused(&run(&dir, &p, &[]), &["many.par:", "end of file"]);
    let sheet = assets("scenes/standard-sheet-32.ron");
    refused(&run(&dir, &sheet, &["--duration", "1e308"]), &["at most 1e9 steps"]);
    refused(&run(&dir, &sheet, &["--dt", "1e-300"]), &["at most 1e9 steps"]);
    let p = edited(&dir, "scenes/standard-sheet-32.ron", "n: 32,", "n: 100000,", "huge.ron");
    refused(&run(&dir, &p, &[]), &["huge.ron", "sheet.n", "expected 2 to 2000 particles a side"]);
    let p = edited(&dir, "scenes/walk.ron", "duration_s: 50.0,", "duration_s: inf,", "forever.ron");
    refused(&run(&dir, &p, &[]), &["forever.ron", "duration"]);
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn every_value_is_checked_where_it_is_read() {
    let dir = temp_dir("values");
    for (rel, from, to, wanted) in [
        ("scenes/standard-sheet-32.ron", "(31, 0)]", "(32, 0)]", "sheet.pinned[1]"),
        ("scenes/standard-sheet-32.ron", "(1000.0, 500.0", "(NaN, 500.0", "sheet.stiffness_n_m[0]"),
        ("scenes/standard-sheet-32.ron", "size_m: 1.0", "size_m: 0.0", "sheet.size_m"),
        ("scenes/standard-sheet-32.ron", "total_mass_kg: 0.2", "total_mass_kg: 0.0", "sheet.total_mass_kg"),
        (
            "scenes/standard-sheet-32.ron",
            "damping_n_s_m: 0.02",
            "damping_n_s_m: -0.02",
            "sheet.damping_n_s_m",
        ),
        ("scenes/standard-sheet-32.ron", "n: 32,", "n: 1,", "sheet.n"),
        ("flex3d/wind.ron", "coefficient: 0.18", "coefficient: -0.18", "friction.coefficient"),
        (
            "oliveira/test-3-sphere-5x5.ron",
            "young_modulus_pa: 1e7",
            "young_modulus_pa: -1e7",
            "material.young_modulus_pa",
        ),
    ] {
        let name = format!("value-{}", Path::new(rel).file_name().unwrap().to_string_lossy());
        let p = edited(&dir, rel, from, to, &name);
        if rel.starts_with("oliveira") {
            // Written beside the assets it names would be outside the scratch folder: name none.
            assert!(!std::fs::read_to_string(&p).unwrap().contains("meshes/"));
        }
        refused(&run(&dir, &p, &[]), &[&name, wanted, "line"]);
    }
    let p = edited(&dir, "flex3d/a2-2-vento.par", "ATRITO = 0.18", "ATRITO = -0.18", "friction.par");
    refused(&run(&dir, &p, &[]), &["friction.par:5:10:", "a number ≥ 0 for `ATRITO`"]);
    let p = edited(&dir, "flex3d/a2-2-vento.par", "(10.0 10.0 10.0)", "(10.0 -10.0 10.0)", "stiffness.par");
    refused(&run(&dir, &p, &[]), &["stiffness.par:14:", "a stiffness ≥ 0"]);
    // Options that do not apply to the scene's kind are refused, not ignored.
    let body = assets("scenes/stand.ron");
    refused(&run(&dir, &body, &["--integrator", "rk4"]), &["does not apply to a body scene"]);
    refused(&run(&dir, &body, &["--friction", "viscous"]), &["does not apply to a body scene"]);
    refused(
        &run(&dir, &assets("scenes/standard-sheet-32.ron"), &["--gravity", "off"]),
        &["does not apply to a sheet"],
    );
    refused(&run(&dir, &body, &["--dt", "0.2", "--duration", "0.1"]), &["no longer than the run"]);
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_run_keeps_its_outputs_whole_and_its_own() {
    let dir = temp_dir("hygiene");
    let out = dir.join("out");
    let curtain = assets("flex3d/curtain.ron");
    // An output that cannot be written fails before the run, not after it.
    std::fs::write(dir.join("file"), "").unwrap();
    let o = anima()
        .args(["run", "--quiet", "--summary"])
        .arg(dir.join("file/summary.json"))
        .arg(&curtain)
        .output()
        .unwrap();
    refused(&o, &["file"]);
    // A reused --out holds only this run's frames.
    let long = anima()
        .args(["run", "--quiet", "--no-pictures", "--duration", "5", "--out"])
        .arg(&out)
        .arg(&curtain)
        .output()
        .unwrap();
    assert!(long.status.success());
    assert!(out.join("cortina_5.OBT").is_file());
    let short = anima()
        .args(["run", "--no-pictures", "--duration", "2", "--out"])
        .arg(&out)
        .arg(&curtain)
        .output()
        .unwrap();
    assert!(short.status.success());
    // Ten frame files (five frames in two formats) and the earlier run's series.json.
    let err = String::from_utf8_lossy(&short.stderr);
    assert!(err.contains("removed 11 output files (frames, animation, series) of an earlier run"), "{err}");
    assert!(out.join("cortina_2.OBT").is_file() && !out.join("cortina_5.OBT").exists());
    assert!(
        all_files(&out).iter().all(|p| !p.file_name().unwrap().to_string_lossy().starts_with('.')),
        "no temporary files"
    );
    // A byte-order mark is accepted in RON as in .PAR.
    let text = std::fs::read_to_string(&curtain).unwrap();
    std::fs::write(dir.join("bom.ron"), format!("\u{feff}{text}")).unwrap();
    assert!(run(&dir, &dir.join("bom.ron"), &["--duration", "1"]).status.success());
    // A .PAR cut inside a UTF-8 character is refused there, not read as Latin-1.
    std::fs::write(
        dir.join("cut.par"),
        "DURAÇÃO = 4\nQUADROS_SEG = 5\nSUPERF\u{cd}".as_bytes().split_last().unwrap().1,
    )
    .unwrap();
    refused(&run(&dir, &dir.join("cut.par"), &[]), &["cut.par:3:7:", "a complete UTF-8 character"]);
    // Not a scene by its name: refused before a byte is read (`/dev/zero` would never end).
    if Path::new("/dev/zero").exists() {
        refused(&run(&dir, Path::new("/dev/zero"), &[]), &["ending in .par or .ron"]);
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A run that overflows is stopped with exit status 2, with the step, and its summary says it: the
/// implicit integrators too, whose overflowing force once left a frozen, finite state (`all_finite: true`
/// and no error). Every one is stopped by its bounds or by the overflow itself.
#[test]
fn a_diverging_run_says_so_with_every_integrator() {
    let dir = temp_dir("diverge");
    let p = edited(
        &dir,
        "scenes/standard-sheet-32.ron",
        "gravity_m_s2: (0.0, 0.0, -9.81)",
        "gravity_m_s2: (0.0, 0.0, -1e200)",
        "overflow.ron",
    );
    for integrator in ["symplectic-euler", "implicit-euler", "bdf2", "generalized-alpha"] {
        let o = run(&dir, &p, &["--integrator", integrator, "--dt", "0.01", "--duration", "0.1"]);
        let err = String::from_utf8_lossy(&o.stderr).into_owned();
        assert_eq!(o.status.code(), Some(2), "{integrator}: {err}");
        assert!(err.contains("step "), "{integrator}: the error names the step: {err}");
        let summary = std::fs::read_to_string(dir.join("out/summary.json")).unwrap();
        assert!(
            summary.contains("\"all_finite\": false") || summary.contains("diverged at step"),
            "{integrator}: {summary}"
        );
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn exit_statuses_are_documented() {
    let help = String::from_utf8_lossy(&anima().arg("--help").output().unwrap().stdout).into_owned();
    assert!(
        help.contains("0 when") && help.contains("1 for bad input") && help.contains("2 when a run diverged"),
        "{help}"
    );
}

/// The help states the limits as they are (a limit changed in `anima_format::limits` changes the help).
#[test]
fn limits_are_documented() {
    use anima_scene::limits::*;
    let help = String::from_utf8_lossy(&anima().arg("--help").output().unwrap().stdout).replace('\n', " ");
    let help = help.split_whitespace().collect::<Vec<_>>().join(" ");
    for stated in [
        format!("{MAX_PARTICLES} particles a scene"),
        format!("{MAX_STEPS:e} steps and {MAX_FRAMES:e} frames a run"),
        format!("{} MiB a file", MAX_FILE_BYTES >> 20),
        format!("{MAX_LENGTH_M:e} m for an object's size"),
        format!("{MAX_BODIES} bodies or joints a skeleton"),
        format!("{MAX_STATES} states, actuators or sensors a controller"),
        format!("{MAX_POPULATION} candidates a generation"),
        format!("{MAX_EVALUATIONS} evaluations an optimisation"),
        format!("{} corners an OBJ face", anima_geom::MAX_FACE_CORNERS),
    ] {
        assert!(help.contains(&stated), "the help says `{stated}`: {help}");
    }
}

#[test]
fn an_interrupted_run_leaves_no_temporary_file() {
    if Command::new("kill").arg("-l").output().is_err() {
        return; // no `kill` to send the signal with
    }
    let dir = temp_dir("interrupt");
    let out = dir.join("out");
    // The theatre curtains write 290 frame files over 145 simulated seconds: long enough to interrupt.
    let mut child = anima()
        .args(["run", "--quiet", "--no-pictures", "--out"])
        .arg(&out)
        .arg(assets("flex3d/a2-4-cortinas.par"))
        .spawn()
        .unwrap();
    std::thread::sleep(std::time::Duration::from_millis(1500));
    Command::new("kill").args(["-INT", &child.id().to_string()]).status().unwrap();
    let status = child.wait().unwrap();
    assert_eq!(status.code(), Some(130), "an interrupt ends the run with status 130");
    let files = all_files(&out);
    assert!(!files.is_empty(), "frames were written before the interrupt");
    let hidden: Vec<_> =
        files.iter().filter(|p| p.file_name().unwrap().to_string_lossy().starts_with('.')).collect();
    assert!(hidden.is_empty(), "temporary files left behind: {hidden:?}");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Round 2: an optimisation spec's name is a plain name, never a path (it becomes two file names in
/// `--out`); nothing is written or deleted outside `--out`.
#[test]
fn spec_names_are_data_not_paths() {
    let dir = temp_dir("spec-names");
    for bad in ["../../escaped/x", "/tmp/anima-escaped", ".hidden"] {
        let spec = dir.join("spec.ron");
        let text = std::fs::read_to_string(assets("optimisations/throw.ron"))
            .unwrap()
            .replace("\"throw-greedy-capped\"", &format!("{bad:?}"))
            .replace("\"../controllers/throw.ron\"", &format!("{:?}", assets("controllers/throw.ron")));
        std::fs::write(&spec, text).unwrap();
        let o = anima()
            .args(["optimise", "--quiet", "--fresh", "--out"])
            .arg(dir.join("out"))
            .arg(&spec)
            .output()
            .unwrap();
        refused(&o, &["spec.ron: line 8, column 5: field `name`", bad]);
        assert!(all_files(&dir).iter().all(|p| p == &spec), "{bad}: nothing written: {:?}", all_files(&dir));
    }
    assert!(!Path::new("/tmp/anima-escaped.log.ron").exists());
    // A budget beyond the limit from the command line is refused before anything runs.
    let o = anima()
        .args(["optimise", "--quiet", "--evaluations", "10000000", "--out"])
        .arg(dir.join("out"))
        .arg(assets("optimisations/throw.ron"))
        .output()
        .unwrap();
    refused(&o, &["anima's limit", "10000000"]);
    assert!(!dir.join("out").join("throw-greedy-capped.log.ron").exists());
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Round 2: an output path where a folder, a device or a FIFO stands is refused before the run, and an
/// existing file outside `--out` is replaced only with `--force`.
#[test]
fn outputs_go_to_new_or_regular_files_only() {
    let dir = temp_dir("output-kinds");
    let curtain = assets("flex3d/curtain.ron");
    let with_summary = |summary: &Path, extra: &[&str]| {
        let mut c = anima();
        c.args(["run", "--quiet", "--no-pictures", "--duration", "1", "--out"]).arg(dir.join("out"));
        c.arg("--summary").arg(summary).args(extra).arg(&curtain).output().unwrap()
    };
    std::fs::create_dir_all(dir.join("folder")).unwrap();
    refused(&with_summary(&dir.join("folder"), &[]), &["is a folder"]);
    refused(&with_summary(Path::new("/"), &["--force"]), &["names no file"]);
    if Path::new("/dev/null").exists() {
        refused(&with_summary(Path::new("/dev/null"), &["--force"]), &["not a regular file"]);
        let o = anima()
            .args(["convert", "--force", "-o", "/dev/null"])
            .arg(assets("flex3d/a2-2-vento.par"))
            .output()
            .unwrap();
        refused(&o, &["not a regular file"]);
    }
    let fifo = dir.join("fifo");
    if Command::new("mkfifo").arg(&fifo).status().is_ok_and(|s| s.success()) {
        refused(&with_summary(&fifo, &["--force"]), &["not a regular file"]);
        assert!(std::fs::symlink_metadata(&fifo).is_ok_and(|m| !m.is_file()), "the FIFO is kept");
    }
    std::fs::write(dir.join("mine.json"), "keep").unwrap();
    refused(&with_summary(&dir.join("mine.json"), &[]), &["pass --force"]);
    assert_eq!(std::fs::read_to_string(dir.join("mine.json")).unwrap(), "keep");
    assert!(with_summary(&dir.join("mine.json"), &["--force"]).status.success());
    // A file in --out is the run's own, however the paths are spelled (here --out relative, --summary
    // absolute).
    std::fs::write(dir.join("out/own.json"), "old").unwrap();
    let o = anima()
        .current_dir(&dir)
        .args(["run", "--quiet", "--no-pictures", "--duration", "1", "--out", "out", "--summary"])
        .arg(dir.join("out/own.json"))
        .arg(&curtain)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(std::fs::read_to_string(dir.join("mine.json")).unwrap().contains("\"steps\""));
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Round 2: a value is checked where it is read (a strain limit that is not a positive strain), and a
/// summary counts what happened with every integrator, adaptive ones included; an adaptive run that
/// crawls ends on its own step budget.
#[test]
fn round_two_values_and_summaries() {
    let dir = temp_dir("round-two");
    for bad in ["Some(-1.0)", "Some(NaN)", "Some(0.0)"] {
        let scene = edited(
            &dir,
            "scenes/drape-sphere-65.ron",
            "self_collision: Modern)",
            &format!("self_collision: Modern, strain_limit: {bad})"),
            "strain.ron",
        );
        refused(&run(&dir, &scene, &[]), &["strain.ron", "strain_limit", "positive, finite strain"]);
    }
    // A Bunny scaled past what f64 can measure: refused by its size, not by a NaN volume.
    let text = std::fs::read_to_string(assets("scenes/drape-bunny-65.ron")).unwrap();
    let bunny = format!("{:?}", assets("meshes/bunny.obj"));
    let huge = dir.join("huge.ron");
    std::fs::write(
        &huge,
        text.replace("length_m: 0.5", "length_m: 1e200").replace("\"../meshes/bunny.obj\"", &bunny),
    )
    .unwrap();
    refused(&run(&dir, &huge, &[]), &["huge.ron", "length_m must be at most 1e6 m"]);
    let sheet = assets("scenes/standard-sheet-64.ron");
    let summary = |out: &Path| std::fs::read_to_string(out.join("summary.json")).unwrap();
    for integrator in ["dopri5", "adaptive-euler"] {
        let o = run(&dir, &sheet, &["--duration", "0.1", "--integrator", integrator]);
        assert!(o.status.success(), "{integrator}: {}", String::from_utf8_lossy(&o.stderr));
        let s = summary(&dir.join("out"));
        assert!(!s.contains("\"steps\": 0,"), "{integrator} counts its steps: {s}");
        assert!(s.contains("\"simulated_seconds\": 0.1"), "{integrator}: {s}");
        assert!(s.contains("\"frames\": 3,"), "{integrator}: {s}");
    }
    // Side inputs are read through the scene's size cap, not whole.
    if Path::new("/dev/zero").exists() {
        refused(&run(&dir, &sheet, &["--reference", "/dev/zero"]), &["/dev/zero", "at most 256 MiB"]);
        let o = anima().args(["convert", "/dev/zero", "-o"]).arg(dir.join("zero.ron")).output().unwrap();
        refused(&o, &["/dev/zero", "at most 256 MiB"]);
    }
    let o = run(&dir, &sheet, &["--duration", "0.4", "--dt", "0.03", "--integrator", "dopri5"]);
    assert_eq!(o.status.code(), Some(2), "a crawling run stops: {}", String::from_utf8_lossy(&o.stderr));
    assert!(summary(&dir.join("out")).contains("adaptive steps, 100 times the 13 steps"));
    // A sizing field whose finest mesh would pass the particle limit is refused where it is written.
    let fine = edited(
        &dir,
        "oliveira/test-2-table-adaptive.ron",
        "remesher: Oliveira(test: 2, short_edge: MinLength, interval_s: 0.001)",
        "remesher: SizingField(min_edge_m: 1e-12, interval_s: 0.001)",
        "fine.ron",
    );
    refused(&run(&dir, &fine, &[]), &["fine.ron", "line 51", "remesher.min_edge_m", "4000000 particles"]);
    // A physics step too long for the contacts: the figure falls through the ground, finite and quiet,
    // unless the run looks (it used to end with the head 8.56 m under the ground, exit 0).
    let text = std::fs::read_to_string(assets("scenes/walk.ron")).unwrap();
    let long = dir.join("long-step.ron");
    let humanoid = format!("{:?}", assets("skeletons/humanoid.ron"));
    let controller = format!("{:?}", assets("controllers/walk-optimised.ron"));
    std::fs::write(
        &long,
        text.replace("dt_s: 0.05", "dt_s: 1.0")
            .replace("substeps: 4", "substeps: 1")
            .replace("\"../skeletons/humanoid.ron\"", &humanoid)
            .replace("\"../controllers/walk-optimised.ron\"", &controller),
    )
    .unwrap();
    let o = run(&dir, &long, &[]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(err.contains("step 2 (t = 2.0000 s): body `head`") && err.contains("went through it"), "{err}");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn controllers_are_checked_against_their_figures_when_read() {
    let dir = temp_dir("controller-binding");
    let humanoid = format!("{:?}", assets("skeletons/humanoid.ron"));
    let thrower = format!("{:?}", assets("skeletons/thrower.ron"));
    // A scene of the walk or the throw with its controller replaced by `controller` (edited from the
    // shipped one: `from` → `to`).
    let scene = |scene: &str, controller: &str, from: &str, to: &str| {
        let c = edited(&dir, &format!("controllers/{controller}"), from, to, "ctl.ron");
        assert!(c.exists());
        let text = std::fs::read_to_string(assets(&format!("scenes/{scene}"))).unwrap();
        let text = text
            .replace("\"../skeletons/humanoid.ron\"", &humanoid)
            .replace("\"../skeletons/thrower.ron\"", &thrower)
            .replace(&format!("\"../controllers/{controller}\""), "\"ctl.ron\"");
        let p = dir.join("scene.ron");
        std::fs::write(&p, text).unwrap();
        p
    };
    // A sensor kind the body's catalogue does not compute: at its line of the controller file.
    let s = scene("walk.ron", "walk-optimised.ron", "kind: \"foot_up\"", "kind: \"foot_upp\"");
    refused(&run(&dir, &s, &[]), &["ctl.ron", "line 122", "unknown sensor kind `foot_upp`"]);
    // A sensor without the side it needs.
    let s = scene(
        "walk.ron",
        "walk-optimised.ron",
        "\"left\",\n                        ],\n                        params: [],\n                    )),\n                    delay: 3.0",
        "],\n                        params: [],\n                    )),\n                    delay: 3.0",
    );
    refused(&run(&dir, &s, &[]), &["ctl.ron", "line 123", "needs a side"]);
    // Procedure arguments: a count the procedure does not take, a body the figure does not have.
    let s = scene(
        "throw.ron",
        "throw-optimised.ron",
        "name: \"release_ball\",\n                        args: []",
        "name: \"release_ball\",\n                        args: [\"now\"]",
    );
    refused(&run(&dir, &s, &[]), &["ctl.ron", "line 150", "`release_ball`", "expected 0 arguments"]);
    let push = "procedure: Some(Call(name: \"push\", args: [\"\", \"tail\", \"10\", \"0\"]))";
    let s = scene("walk.ron", "walk-optimised.ron", "procedure: None", push);
    refused(&run(&dir, &s, &[]), &["ctl.ron", "no body named `tail`"]);
    let push = "procedure: Some(Call(name: \"push\", args: [\"\", \"head\", \"ten\"]))";
    let s = scene("walk.ron", "walk-optimised.ron", "procedure: None", push);
    refused(&run(&dir, &s, &[]), &["ctl.ron", "expected 4 arguments"]);
    let copy = "procedure: Some(Call(name: \"copy_params\", args: [\"W-LEGS/T1/delay\", \"nothing\"]))";
    let s = scene("walk.ron", "walk-optimised.ron", "procedure: None", copy);
    refused(&run(&dir, &s, &[]), &["ctl.ron", "`copy_params`", "argument 1", "`nothing`"]);
    // An optimisation spec's controller is checked against the objective's figure.
    edited(&dir, "controllers/walk.ron", "kind: \"foot_up\"", "kind: \"foot_upp\"", "walk-bad.ron");
    let spec =
        edited(&dir, "optimisations/walk-cmaes.ron", "../controllers/walk.ron", "walk-bad.ron", "spec.ron");
    let o = anima().args(["optimise", "--out"]).arg(dir.join("opt")).arg(&spec).output().unwrap();
    refused(&o, &["walk-bad.ron", "unknown sensor kind `foot_upp`"]);
    std::fs::remove_dir_all(&dir).unwrap();
}
