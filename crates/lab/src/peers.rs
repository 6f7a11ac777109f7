//! `cargo xtask bench --peers`: anima beside the simulators `benchmarks.md` names, on the same scenes,
//! timed alternately in one run. A ratio against a number recorded on another day measures the day as
//! much as the simulator; here every round runs anima and the peer back to back (in alternating order),
//! so that the machine's load drifts over both alike, and each ratio is taken within its round.
//!
//! The peers are the scripts of the benchmark's peer folder (NVIDIA Warp on the standard sheet, MuJoCo
//! on the standard biped), run by a Python that has them installed. Nothing is installed here: the
//! folder is named by `ANIMA_PEERS` and the interpreter by `ANIMA_PEERS_PYTHON` (default `python3`).
//! Without them the run says so, times anima alone and leaves `docs/benchmarks-peers.md` as it was.
//!
//! Two times per run: the whole process (start-up, scene building, Warp's kernel compilation and
//! Python's imports included: what a user waits for) and the simulation loop alone (each program's own
//! timer: anima's summary `wall_seconds`, the peers' `wall_s`).

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Instant;

use anyhow::{Context, Result, bail};

use crate::repo::Repo;

/// Rounds after the warm-up round, each running anima and the peer once.
pub const ROUNDS: usize = 5;

/// One scene as anima and a peer run it.
#[derive(Debug, Clone)]
pub struct Pair {
    pub title: &'static str,
    /// The scene file under `assets/`, and extra arguments of `anima run`.
    pub scene: &'static str,
    pub anima_args: Vec<String>,
    pub peer_name: &'static str,
    /// The peer's script and its arguments.
    pub peer_script: &'static str,
    pub peer_args: Vec<String>,
    pub kind: PairKind,
}

/// What the two runs are compared on besides time.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum PairKind {
    /// The standard sheet: centre of mass at 1 s against the reference of `benchmarks.md`.
    Sheet { n: usize },
    /// The standard biped: hip height and pitch at the end.
    Biped,
}

/// The pairs of `benchmarks.md`: the standard sheet at N = 32 and 64 with symplectic Euler at the common
/// steps, anima on one thread and on every core (its default there), and the standard biped, 10 s at
/// 1 ms.
pub fn pairs() -> Vec<Pair> {
    let sheet = |n: usize, dt: &str, one_thread: bool| {
        let mut anima_args: Vec<String> =
            vec!["--integrator".into(), "symplectic-euler".into(), "--dt".into(), dt.into()];
        if one_thread {
            anima_args.push("--one-thread".into());
        }
        Pair {
            title: match (n, one_thread) {
                (64, true) => "Standard sheet, N = 64, 10⁻⁴ s, 1 s: anima on one thread",
                (64, false) => "Standard sheet, N = 64, 10⁻⁴ s, 1 s: anima on every core (its default)",
                (_, true) => "Standard sheet, N = 32, 2·10⁻⁴ s, 1 s: anima on one thread",
                (_, false) => "Standard sheet, N = 32, 2·10⁻⁴ s, 1 s: anima on every core (its default)",
            },
            scene: if n == 64 { "scenes/standard-sheet-64.ron" } else { "scenes/standard-sheet-32.ron" },
            anima_args,
            peer_name: "NVIDIA Warp (CPU, f32, symplectic Euler)",
            peer_script: "cloth_warp.py",
            peer_args: vec![n.to_string(), dt.into()],
            kind: PairKind::Sheet { n },
        }
    };
    vec![
        sheet(64, "1e-4", true),
        sheet(64, "1e-4", false),
        sheet(32, "2e-4", true),
        sheet(32, "2e-4", false),
        Pair {
            title: "Standard biped, 10 s at 1 ms",
            scene: "scenes/standard-biped.ron",
            anima_args: vec![],
            peer_name: "MuJoCo (built-in position servos, whole run in C)",
            peer_script: "biped_mujoco.py",
            peer_args: vec!["0.001".into(), "--mode".into(), "servo".into()],
            kind: PairKind::Biped,
        },
    ]
}

/// The peers' Python and scripts, when `ANIMA_PEERS` names a folder whose scripts that Python can run.
#[derive(Debug, Clone)]
pub struct Peers {
    pub python: PathBuf,
    pub scripts: PathBuf,
    /// What the Python reports of itself and the peers (`warp x.y, mujoco x.y, Python x.y`).
    pub versions: String,
}

impl Peers {
    /// The peers, or why they cannot run.
    pub fn from_env() -> std::result::Result<Self, String> {
        let scripts = std::env::var_os("ANIMA_PEERS")
            .map(PathBuf::from)
            .ok_or("ANIMA_PEERS is not set (the folder holding cloth_warp.py and biped_mujoco.py)")?;
        let python =
            PathBuf::from(std::env::var_os("ANIMA_PEERS_PYTHON").unwrap_or_else(|| "python3".into()));
        Self::from_folder(&scripts, &python)
    }

    /// The peers of the script folder `scripts`, run by `python`, or why they cannot run.
    pub fn from_folder(scripts: &Path, python: &Path) -> std::result::Result<Self, String> {
        if !scripts.join("cloth_warp.py").is_file() || !scripts.join("biped_mujoco.py").is_file() {
            return Err(format!("{} holds no cloth_warp.py and biped_mujoco.py", scripts.display()));
        }
        let probe = "import sys, warp, mujoco; \
                     print(f'warp {warp.__version__}, mujoco {mujoco.__version__}, Python {sys.version.split()[0]}')";
        let out = Command::new(python)
            .args(["-c", probe])
            .output()
            .map_err(|e| format!("cannot start {}: {e}", python.display()))?;
        if !out.status.success() {
            let err = String::from_utf8_lossy(&out.stderr);
            let last = err.lines().last().unwrap_or("").to_string();
            return Err(format!("{} cannot import warp and mujoco: {last}", python.display()));
        }
        let versions = String::from_utf8_lossy(&out.stdout).trim().to_string();
        Ok(Self { python: python.to_path_buf(), scripts: scripts.to_path_buf(), versions })
    }
}

/// One timed run.
#[derive(Debug, Clone, Copy, Default)]
pub struct Timed {
    pub process_s: f64,
    pub loop_s: f64,
    /// Sheet: centre-of-mass error (m). Biped: final hip height (m).
    pub metric: f64,
    /// Biped: final pitch (rad); unused for the sheet.
    pub metric2: f64,
}

/// The reference centre of mass at 1 s of `benchmarks.md` (f64, symplectic Euler at 10⁻⁵ s).
fn reference_com(n: usize) -> [f64; 3] {
    if n == 64 { [0.5000605, -0.4684101, 1.4631486] } else { [0.4999997, -0.4792614, 1.4655051] }
}

fn distance(a: [f64; 3], b: [f64; 3]) -> f64 {
    ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
}

fn array3(v: &serde_json::Value) -> Option<[f64; 3]> {
    let a = v.as_array()?;
    Some([a.first()?.as_f64()?, a.get(1)?.as_f64()?, a.get(2)?.as_f64()?])
}

/// Runs `anima run` on the pair's scene once.
pub fn run_anima(repo: &Repo, anima: &Path, pair: &Pair, out: &Path) -> Result<Timed> {
    let summary = out.join("summary.json");
    let started = Instant::now();
    let status = Command::new(anima)
        .arg("run")
        .arg(repo.assets(pair.scene))
        .args(&pair.anima_args)
        .args(["--no-frames", "--no-pictures", "--quiet", "--out"])
        .arg(out)
        .status()
        .with_context(|| format!("starting {}", anima.display()))?;
    let process_s = started.elapsed().as_secs_f64();
    if !status.success() {
        bail!("anima run {} failed: {status}", pair.scene);
    }
    let json: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&summary)?)?;
    let loop_s = json["wall_seconds"].as_f64().context("summary without wall_seconds")?;
    let (metric, metric2) = match pair.kind {
        PairKind::Sheet { n } => {
            let com = array3(&json["center_of_mass"]).context("summary without center_of_mass")?;
            (distance(com, reference_com(n)), 0.0)
        }
        PairKind::Biped => {
            let model = &json["models"][0];
            (
                model["hip_height_m"].as_f64().unwrap_or(f64::NAN),
                model["hip_pitch_rad"].as_f64().unwrap_or(f64::NAN),
            )
        }
    };
    Ok(Timed { process_s, loop_s, metric, metric2 })
}

/// Runs the pair's peer script once and reads its `RESULT {json}` line.
pub fn run_peer(peers: &Peers, pair: &Pair) -> Result<Timed> {
    let started = Instant::now();
    let out = Command::new(&peers.python)
        .arg(peers.scripts.join(pair.peer_script))
        .args(&pair.peer_args)
        .output()
        .with_context(|| format!("starting {}", pair.peer_script))?;
    let process_s = started.elapsed().as_secs_f64();
    let stdout = String::from_utf8_lossy(&out.stdout);
    let Some(line) = stdout.lines().find_map(|l| l.strip_prefix("RESULT ")) else {
        bail!(
            "{} printed no RESULT line ({}): {}",
            pair.peer_script,
            out.status,
            String::from_utf8_lossy(&out.stderr).lines().last().unwrap_or("")
        );
    };
    let json: serde_json::Value = serde_json::from_str(line)?;
    let loop_s = json["wall_s"].as_f64().context("RESULT without wall_s")?;
    let (metric, metric2) = match pair.kind {
        PairKind::Sheet { n } => {
            let com = array3(&json["com"]).context("RESULT without com")?;
            (distance(com, reference_com(n)), 0.0)
        }
        PairKind::Biped => (
            json["hip_z_final"].as_f64().unwrap_or(f64::NAN),
            json["pitch_final"].as_f64().unwrap_or(f64::NAN),
        ),
    };
    Ok(Timed { process_s, loop_s, metric, metric2 })
}

/// Median, least and largest of `v` (not empty).
fn spread(v: &[f64]) -> (f64, f64, f64) {
    let mut s = v.to_vec();
    s.sort_by(f64::total_cmp);
    let mid = if s.len() % 2 == 1 { s[s.len() / 2] } else { 0.5 * (s[s.len() / 2 - 1] + s[s.len() / 2]) };
    (mid, s[0], s[s.len() - 1])
}

fn cell(v: &[f64], unit: &str, digits: usize) -> String {
    let (m, lo, hi) = spread(v);
    format!("{m:.digits$}{unit} ({lo:.digits$}–{hi:.digits$})")
}

/// The machine, for the report's header: CPU model and logical cores.
fn machine() -> String {
    let model = std::fs::read_to_string("/proc/cpuinfo")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("model name"))
                .and_then(|l| l.split(':').nth(1))
                .map(|m| m.trim().to_string())
        })
        .unwrap_or_else(|| "unknown CPU".into());
    let cores = std::thread::available_parallelism().map_or(0, |n| n.get());
    format!("{model}, {cores} logical cores")
}

/// Times every pair: a warm-up round, then [`ROUNDS`] rounds of one anima run and one peer run in
/// alternating order. Writes `docs/benchmarks-peers.md` when the peers can run; otherwise prints why and
/// anima's times alone. `anima` is the release binary to time.
pub fn run(repo: &Repo, anima: &Path) -> Result<()> {
    let peers = Peers::from_env();
    let scratch = repo.cache("peers");
    std::fs::create_dir_all(&scratch)?;
    let mut doc = format!(
        "# anima beside its peers, timed in one run\n\n_Generated by `cargo xtask bench --peers` on {}; do not edit._\n\n\
         Machine: {}. anima {} (release build, f64; on one thread where a section says so, else with its \
         default threads: every core for these sheets, one for the biped)",
        crate::report::today(),
        machine(),
        env!("CARGO_PKG_VERSION"),
    );
    match &peers {
        Ok(p) => {
            let _ = writeln!(doc, "; {}.\n", p.versions);
        }
        Err(why) => {
            eprintln!(
                "anima-lab: the peers cannot run ({why}); timing anima alone, docs/benchmarks-peers.md is left as it was"
            );
            doc.push_str(".\n\n");
        }
    }
    doc.push_str(
        "Each scene ran once as a warm-up, then in rounds of one anima run and one peer run, the order alternating \
         from round to round, so that the shared machine's load falls on both alike. Times are medians with the \
         least and largest in brackets; a ratio is the peer's time over anima's within one round (above 1: anima is \
         faster), its median and range over the rounds. *Loop*: the simulation loop alone, by each program's own \
         timer. *Process*: the whole process as a user waits for it (start-up, scene building, imports and Warp's \
         kernel compilation included).\n\n",
    );
    for pair in pairs() {
        eprintln!("anima-lab: peers — {} …", pair.title);
        let out = scratch.join(pair.scene.replace(['/', '.'], "-"));
        let mut anima_runs = Vec::new();
        let mut peer_runs = Vec::new();
        // Warm-up (caches, Warp's kernel cache, the page cache).
        run_anima(repo, anima, &pair, &out)?;
        if let Ok(p) = &peers {
            run_peer(p, &pair)?;
        }
        for round in 0..ROUNDS {
            let anima_first = round % 2 == 0;
            if anima_first {
                anima_runs.push(run_anima(repo, anima, &pair, &out)?);
            }
            if let Ok(p) = &peers {
                peer_runs.push(run_peer(p, &pair)?);
            }
            if !anima_first {
                anima_runs.push(run_anima(repo, anima, &pair, &out)?);
            }
        }
        section(&mut doc, &pair, &anima_runs, &peer_runs);
    }
    print!("{doc}");
    if peers.is_ok() {
        repo.write_text("docs/benchmarks-peers.md", &doc)?;
    }
    Ok(())
}

fn section(doc: &mut String, pair: &Pair, anima: &[Timed], peer: &[Timed]) {
    let _ = writeln!(
        doc,
        "## {}\n\n`anima run assets/{} {}` beside `{} {}`.\n",
        pair.title,
        pair.scene,
        pair.anima_args.join(" "),
        pair.peer_script,
        pair.peer_args.join(" ")
    );
    let get = |runs: &[Timed], f: fn(&Timed) -> f64| runs.iter().map(f).collect::<Vec<f64>>();
    let ratios =
        |f: fn(&Timed) -> f64| anima.iter().zip(peer).map(|(a, p)| f(p) / f(a)).collect::<Vec<f64>>();
    let (what, unit, scale, digits) = match pair.kind {
        PairKind::Sheet { .. } => ("centre-of-mass error at 1 s", " mm", 1e3, 2),
        PairKind::Biped => ("final hip height", " m", 1.0, 3),
    };
    let metric = |runs: &[Timed]| runs.iter().map(|t| t.metric * scale).collect::<Vec<f64>>();
    let _ = writeln!(doc, "| | loop | process | {what} |\n|---|---|---|---|");
    let _ = writeln!(
        doc,
        "| anima | {} | {} | {} |",
        cell(&get(anima, |t| t.loop_s), " s", 3),
        cell(&get(anima, |t| t.process_s), " s", 3),
        cell(&metric(anima), unit, digits)
    );
    if peer.is_empty() {
        let _ = writeln!(doc, "| {} | not run | not run | — |\n", pair.peer_name);
        return;
    }
    let _ = writeln!(
        doc,
        "| {} | {} | {} | {} |",
        pair.peer_name,
        cell(&get(peer, |t| t.loop_s), " s", 3),
        cell(&get(peer, |t| t.process_s), " s", 3),
        cell(&metric(peer), unit, digits)
    );
    let _ = writeln!(
        doc,
        "| ratio, peer / anima | {} | {} | |",
        cell(&ratios(|t| t.loop_s), "×", 2),
        cell(&ratios(|t| t.process_s), "×", 2)
    );
    if pair.kind == PairKind::Biped {
        let pitch = |runs: &[Timed]| runs.iter().map(|t| t.metric2).collect::<Vec<f64>>();
        let _ = writeln!(
            doc,
            "\nFinal pitch (rad): anima {}, {} {}. Steps per second in the loop (10 000 steps): anima {}, the peer {}.",
            cell(&pitch(anima), "", 3),
            pair.peer_name,
            cell(&pitch(peer), "", 3),
            cell(&anima.iter().map(|t| 10_000.0 / t.loop_s).collect::<Vec<_>>(), "", 0),
            cell(&peer.iter().map(|t| 10_000.0 / t.loop_s).collect::<Vec<_>>(), "", 0),
        );
    }
    doc.push('\n');
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn spread_gives_the_median_and_the_range() {
        assert_eq!(spread(&[3.0, 1.0, 2.0]), (2.0, 1.0, 3.0));
        assert_eq!(spread(&[4.0, 1.0, 2.0, 3.0]), (2.5, 1.0, 4.0));
    }

    #[test]
    fn without_the_peers_the_reason_is_given() {
        // A folder without the scripts is refused with its name.
        let dir = std::env::temp_dir();
        let err = Peers::from_folder(&dir, Path::new("python3")).unwrap_err();
        assert!(err.contains("cloth_warp.py"), "{err}");
    }
}
