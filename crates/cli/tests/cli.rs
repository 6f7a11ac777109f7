//! The `anima` binary as a user runs it.

use std::path::{Path, PathBuf};
use std::process::Command;

fn anima() -> Command {
    Command::new(env!("CARGO_BIN_EXE_anima"))
}

fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("anima-cli-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn assets() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets/flex3d")
}

#[test]
fn default_scene_writes_frames_picture_and_summary() {
    let out = temp_dir("default");
    let status = anima().args(["run", "--quiet", "--duration", "1", "--out"]).arg(&out).status().unwrap();
    assert!(status.success());
    for name in ["toalha_1.OBT", "toalha_2.OBT", "toalha_2.obj", "final.png", "frames.png", "summary.json"] {
        assert!(out.join(name).is_file(), "{name} missing");
    }
    let summary: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("summary.json")).unwrap()).unwrap();
    for key in [
        "steps",
        "frames",
        "wall_seconds",
        "all_finite",
        "max_speed",
        "kinetic_energy",
        "penetrations",
        "max_strain",
    ] {
        assert!(summary.get(key).is_some(), "summary lacks `{key}`");
    }
    assert_eq!(summary["steps"], 1000);
    assert_eq!(summary["all_finite"], true);
    std::fs::remove_dir_all(&out).unwrap();
}

#[test]
fn convert_then_run_gives_the_same_frames_as_the_script() {
    let dir = temp_dir("convert");
    let ron = dir.join("curtain.ron");
    let par = assets().join("fig6-2-cortina.par");
    assert!(
        anima()
            .arg("convert")
            .arg(&par)
            .arg("-o")
            .arg(&ron)
            .arg("--gravity")
            .arg("on")
            .status()
            .unwrap()
            .success()
    );
    let run = |scene: &Path, out: &str| {
        let out = dir.join(out);
        let ok = anima()
            .args(["run", "--quiet", "--no-pictures", "--duration", "2", "--out"])
            .arg(&out)
            .arg(scene)
            .status()
            .unwrap()
            .success();
        assert!(ok);
        std::fs::read(out.join("cortina_2.OBT")).unwrap()
    };
    assert_eq!(run(&par, "from-par"), run(&ron, "from-ron"));
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_malformed_script_is_refused_with_file_line_and_column() {
    let dir = temp_dir("malformed");
    let path = dir.join("bad.par");
    let good = std::fs::read_to_string(assets().join("a2-2-vento.par")).unwrap();
    std::fs::write(&path, good.replace("DELTA_t = 0.001", "DELTA_t = fast")).unwrap();
    let out = anima().args(["run", "--quiet", "--out"]).arg(dir.join("out")).arg(&path).output().unwrap();
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("bad.par:3:11"), "{err}");
    assert!(err.contains("fast"), "{err}");
    assert!(!dir.join("out").exists(), "nothing is written for a scene that does not parse");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_diverging_run_fails_and_names_the_step() {
    let out = temp_dir("diverge");
    let o = anima()
        .args([
            "run",
            "--quiet",
            "--no-pictures",
            "--no-frames",
            "--dt",
            "0.5",
            "--duration",
            "100000",
            "--out",
        ])
        .arg(&out)
        .arg(assets().join("curtain.ron"))
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("non-finite at step"), "{err}");
    let summary: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["all_finite"], false);
    assert!(summary["non_finite"]["step"].as_u64().unwrap() > 0);
    std::fs::remove_dir_all(&out).unwrap();
}

#[test]
fn standard_sheet_runs_and_compares_with_a_reference() {
    let dir = temp_dir("sheet");
    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets/scenes/standard-sheet-32.ron");
    let run = |out: &str, extra: &[&str]| -> serde_json::Value {
        let out = dir.join(out);
        let ok = anima()
            .args(["run", "--quiet", "--no-frames", "--duration", "0.1", "--out"])
            .arg(&out)
            .args(extra)
            .arg(&scene)
            .status()
            .unwrap()
            .success();
        assert!(ok);
        serde_json::from_slice(&std::fs::read(out.join("summary.json")).unwrap()).unwrap()
    };
    let first = run("a", &[]);
    assert_eq!(first["steps"], 500);
    assert_eq!(first["springs"], 2 * 32 * 31 + 2 * 31 * 31 + 2 * 32 * 30);
    assert!(first["center_of_mass"].as_array().unwrap().len() == 3);
    assert!(first["max_strain"].as_f64().unwrap() > 0.0);
    assert!(dir.join("a/final.png").is_file() && dir.join("a/final.obj").is_file());
    let reference = dir.join("a/final.obj");
    let second = run("b", &["--reference", reference.to_str().unwrap()]);
    // Same scene, same result; the OBJ holds 6 decimals.
    assert!(second["rms_to_reference"].as_f64().unwrap() < 1e-6, "{second}");
    let rk4 = run("c", &["--integrator", "rk4", "--reference", reference.to_str().unwrap()]);
    let d = rk4["rms_to_reference"].as_f64().unwrap();
    assert!(d > 1e-7 && d < 1e-2, "RK4 differs from symplectic Euler by a little: {d}");
    std::fs::remove_dir_all(&dir).unwrap();
}
