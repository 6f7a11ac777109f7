//! `anima view` in headless Chromium, on a sheet run and a walk run: the page loads without a console
//! error, plays, and once its timeline is scrubbed to frame k shows frame k's positions (the sheet's
//! against the run's `sheet_<k>.obj`, the walker's pelvis against the file's keyframe k); a screenshot
//! of each is left in the target folder for a person to look at. Ctrl-C ends the server cleanly.
//! `anima run --live` in the same Chromium: a slider moved on the live page of a paused walk changes
//! the running controller.
//!
//! Ignored by `cargo test`: it needs Chromium (Debian's `chromium`, or the binary named by
//! `ANIMA_CHROMIUM`). `cargo xtask test --viewer` installs it when it is missing and runs these.

use std::io::{BufRead, BufReader};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

use serde_json::Value;

mod common;

use common::{anima, temp_dir};

fn scenes() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets/scenes")
}

fn run(scene: &str, duration: &str, out: &Path) {
    let status = anima()
        .args(["run", "--quiet", "--export", "gltf", "--duration", duration, "--out"])
        .arg(out)
        .arg(scenes().join(scene))
        .status()
        .unwrap();
    assert!(status.success(), "anima run {scene}");
}

/// `anima view` on a folder, ended by SIGINT (Ctrl-C) when dropped.
struct Viewer {
    child: Child,
    url: String,
}

impl Viewer {
    fn start(dir: &Path) -> Viewer {
        let mut child =
            anima().args(["view", "--port", "0"]).arg(dir).stdout(Stdio::piped()).spawn().unwrap();
        let mut line = String::new();
        BufReader::new(child.stdout.take().unwrap()).read_line(&mut line).unwrap();
        let url = line.split_whitespace().find(|w| w.starts_with("http://127.0.0.1:")).map(str::to_owned);
        let url = url.unwrap_or_else(|| panic!("no address in {line:?}"));
        Viewer { child, url }
    }

    /// Ctrl-C, as a person ends it: the server stops and the command exits with success.
    fn interrupt(mut self) {
        let pid = self.child.id().to_string();
        assert!(Command::new("kill").args(["-INT", &pid]).status().unwrap().success());
        let status =
            wait(&mut self.child, Duration::from_secs(10)).expect("anima view did not end on SIGINT");
        assert!(status.success(), "anima view ended with {status} on SIGINT");
    }
}

impl Drop for Viewer {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

fn wait(child: &mut Child, limit: Duration) -> Option<std::process::ExitStatus> {
    let start = Instant::now();
    while start.elapsed() < limit {
        if let Some(status) = child.try_wait().unwrap() {
            return Some(status);
        }
        std::thread::sleep(Duration::from_millis(50));
    }
    let _ = child.kill();
    None
}

/// Headless Chromium on `url` with `args` (`--dump-dom` or `--screenshot=…`); its standard output.
/// WebGL runs on SwiftShader (no GPU needed); virtual time lets the page's timers run at once.
fn chromium(url: &str, profile: &Path, args: &[&str]) -> String {
    let program = std::env::var("ANIMA_CHROMIUM").unwrap_or_else(|_| "chromium".to_owned());
    let mut child = Command::new(&program)
        .args([
            "--headless",
            "--no-sandbox",
            "--use-angle=swiftshader",
            "--enable-unsafe-swiftshader",
            "--window-size=1280,720",
            "--hide-scrollbars",
            "--virtual-time-budget=20000",
        ])
        .arg(format!("--user-data-dir={}", profile.display()))
        .args(args)
        .arg(url)
        .stdout(Stdio::piped())
        .stderr(Stdio::null())
        .spawn()
        .unwrap_or_else(|e| panic!("cannot start {program} ({e}): `cargo xtask test --viewer` installs it"));
    let mut out = String::new();
    let mut stdout = child.stdout.take().unwrap();
    let reader = std::thread::spawn(move || {
        std::io::Read::read_to_string(&mut stdout, &mut out).unwrap();
        out
    });
    let status = wait(&mut child, Duration::from_secs(120)).expect("chromium took over 120 s");
    assert!(status.success(), "chromium ended with {status}");
    reader.join().unwrap()
}

/// Chromium driven through the DevTools protocol on a pipe (`--remote-debugging-pipe`: commands on
/// its fd 3, answers and events on its fd 4, each a JSON message ended by a NUL byte), so the page
/// runs in real time (under `--virtual-time-budget` a headless page draws almost no frames) and every
/// console message and uncaught exception is seen, network errors included.
struct DevTools {
    child: Child,
    to_browser: std::process::ChildStdin,
    from_browser: std::sync::mpsc::Receiver<Value>,
    next_id: u64,
    session: Option<String>,
    /// Console errors, exceptions and error log entries, as text.
    errors: Vec<String>,
}

impl DevTools {
    fn start(profile: &Path) -> DevTools {
        let program = std::env::var("ANIMA_CHROMIUM").unwrap_or_else(|_| "chromium".to_owned());
        // The shell hands our stdin to Chromium as fd 3 and our stdout as fd 4.
        let mut child = Command::new("bash")
            .args(["-c", "exec \"$0\" \"$@\" 3<&0 4>&1 0</dev/null 1>/dev/null", &program])
            .args(["--headless", "--no-sandbox", "--use-angle=swiftshader", "--enable-unsafe-swiftshader"])
            .args(["--window-size=1280,720", "--remote-debugging-pipe", "about:blank"])
            .arg(format!("--user-data-dir={}", profile.display()))
            .stdin(Stdio::piped())
            .stdout(Stdio::piped())
            .stderr(Stdio::null())
            .spawn()
            .unwrap_or_else(|e| {
                panic!("cannot start {program} ({e}): `cargo xtask test --viewer` installs it")
            });
        let to_browser = child.stdin.take().unwrap();
        let mut stdout = BufReader::new(child.stdout.take().unwrap());
        let (send, from_browser) = std::sync::mpsc::channel();
        std::thread::spawn(move || {
            let mut message = Vec::new();
            while stdout.read_until(0, &mut message).is_ok_and(|n| n > 0) {
                message.pop();
                if let Ok(v) = serde_json::from_slice(&message)
                    && send.send(v).is_err()
                {
                    return;
                }
                message.clear();
            }
        });
        let mut tools =
            DevTools { child, to_browser, from_browser, next_id: 0, session: None, errors: Vec::new() };
        let target = tools.call("Target.createTarget", serde_json::json!({ "url": "about:blank" }));
        let target_id = target["targetId"].clone();
        let attached = tools
            .call("Target.attachToTarget", serde_json::json!({ "targetId": target_id, "flatten": true }));
        tools.session = Some(attached["sessionId"].as_str().unwrap().to_owned());
        for domain in ["Runtime.enable", "Log.enable", "Page.enable"] {
            tools.call(domain, serde_json::json!({}));
        }
        tools
    }

    /// Sends a command (to the page once attached) and returns its result; events that arrive
    /// meanwhile are kept when they are errors.
    fn call(&mut self, method: &str, params: Value) -> Value {
        self.next_id += 1;
        let id = self.next_id;
        let mut message = serde_json::json!({ "id": id, "method": method, "params": params });
        if let Some(s) = &self.session {
            message["sessionId"] = Value::String(s.clone());
        }
        let mut bytes = serde_json::to_vec(&message).unwrap();
        bytes.push(0);
        std::io::Write::write_all(&mut self.to_browser, &bytes).unwrap();
        loop {
            let reply =
                self.from_browser.recv_timeout(Duration::from_secs(60)).expect("no answer from chromium");
            if reply["id"] == id {
                assert!(reply.get("error").is_none(), "{method}: {reply}");
                return reply["result"].clone();
            }
            self.keep_error(&reply);
        }
    }

    fn keep_error(&mut self, event: &Value) {
        let p = &event["params"];
        match event["method"].as_str() {
            Some("Runtime.consoleAPICalled") if p["type"] == "error" || p["type"] == "assert" => {
                self.errors.push(format!("console.{}: {}", p["type"], p["args"]))
            }
            Some("Runtime.exceptionThrown") => {
                self.errors.push(format!("exception: {}", p["exceptionDetails"]))
            }
            Some("Log.entryAdded") if p["entry"]["level"] == "error" => {
                self.errors.push(format!("log: {}", p["entry"]))
            }
            _ => {}
        }
    }

    /// A JavaScript expression's value in the page.
    fn evaluate(&mut self, expression: &str) -> Value {
        let r = self
            .call("Runtime.evaluate", serde_json::json!({ "expression": expression, "returnByValue": true }));
        r["result"]["value"].clone()
    }
}

impl Drop for DevTools {
    /// Closes the browser as a person would (`Browser.close`), so that its helper processes end with
    /// it and stop writing into the profile; killed only if it has not gone in 10 s.
    fn drop(&mut self) {
        let mut close =
            serde_json::to_vec(&serde_json::json!({ "id": 0, "method": "Browser.close" })).unwrap();
        close.push(0);
        if std::io::Write::write_all(&mut self.to_browser, &close).is_ok() {
            let start = Instant::now();
            while start.elapsed() < Duration::from_secs(10) {
                if matches!(self.child.try_wait(), Ok(Some(_))) {
                    return;
                }
                std::thread::sleep(Duration::from_millis(50));
            }
        }
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

/// Removes a test's directory once the browser's last helper process has let go of its profile
/// (a renderer can outlive the browser by a moment and write a file after the first attempt).
fn remove_test_dir(dir: &Path) {
    let start = Instant::now();
    while let Err(e) = std::fs::remove_dir_all(dir) {
        assert!(start.elapsed() < Duration::from_secs(30), "{}: {e}", dir.display());
        std::thread::sleep(Duration::from_millis(200));
    }
}

/// The page's self test at frame `k` (`?test=k`): it plays, its timeline is scrubbed to frame k, and
/// it writes what it shows as JSON into `<pre id="result">`. No console error on the way.
fn self_test(url: &str, profile: &Path, k: usize) -> Value {
    let mut page = DevTools::start(profile);
    page.call("Page.navigate", serde_json::json!({ "url": format!("{url}?test={k}") }));
    let start = Instant::now();
    let text = loop {
        let text = page.evaluate("document.getElementById('result')?.textContent ?? ''");
        if text.as_str().is_some_and(|t| !t.is_empty()) {
            break text.as_str().unwrap().to_owned();
        }
        assert!(
            start.elapsed() < Duration::from_secs(90),
            "the page wrote no result in 90 s: {:?}",
            page.errors
        );
        std::thread::sleep(Duration::from_millis(200));
    };
    let result: Value = serde_json::from_str(&text).unwrap();
    assert_eq!(page.errors, Vec::<String>::new(), "console errors on the page");
    assert_eq!(result["errors"], serde_json::json!([]), "errors the page caught");
    let short: String = text.chars().take(300).collect();
    assert_eq!(result["played"], true, "the page did not play: {short}");
    assert_eq!(result["frame"], k, "scrubbed to frame {k}, the page shows {}", result["frame"]);
    assert_eq!(result["shown"]["frame"], k);
    result
}

/// A screenshot of frame `k` into the target folder; it must not be blank.
fn screenshot(url: &str, profile: &Path, k: usize, name: &str) -> PathBuf {
    let png = Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("viewer-{name}.png"));
    let _ = std::fs::remove_file(&png);
    chromium(&format!("{url}?frame={k}"), profile, &[&format!("--screenshot={}", png.display())]);
    let size = std::fs::metadata(&png).map(|m| m.len()).unwrap_or(0);
    // A blank 1280 × 720 page compresses to a few kilobytes; the cloth, plots and text take more.
    assert!(size > 20_000, "{} is {size} bytes: blank?", png.display());
    eprintln!("screenshot: {}", png.display());
    png
}

fn obj_positions(path: &Path) -> Vec<[f64; 3]> {
    std::fs::read_to_string(path)
        .unwrap()
        .lines()
        .filter_map(|l| l.strip_prefix("v "))
        .map(|l| {
            let c: Vec<f64> = l.split_whitespace().map(|x| x.parse().unwrap()).collect();
            [c[0], c[1], c[2]]
        })
        .collect()
}

/// The one cloth the page shows is the run's frame in `obj`. Sheets and drapes have z up, glTF's y:
/// (x, y, z) shows as (x, z, −y). The file holds f32 positions.
fn assert_shows_obj(result: &Value, obj: &Path) {
    let meshes = result["shown"]["meshes"].as_array().unwrap();
    assert_eq!(meshes.len(), 1, "one cloth");
    let shown: Vec<f64> =
        meshes[0]["positions"].as_array().unwrap().iter().map(|v| v.as_f64().unwrap()).collect();
    let run_frame = obj_positions(obj);
    assert_eq!(shown.len(), 3 * run_frame.len(), "vertices shown against {}", obj.display());
    let mut worst = 0.0f64;
    for (i, p) in run_frame.iter().enumerate() {
        let expected = [p[0], p[2], -p[1]];
        for a in 0..3 {
            worst = worst.max((shown[3 * i + a] - expected[a]).abs());
        }
    }
    assert!(worst < 1e-5, "the page is {worst} m from the run's {}", obj.display());
}

#[test]
#[ignore = "needs chromium: cargo xtask test --viewer"]
fn viewer_plays_a_sheet_and_shows_the_frame_scrubbed_to() {
    let dir = temp_dir("sheet");
    let out = dir.join("out");
    // The 32 × 32 standard sheet, 1 s at 30 frames a second: 31 keyframes.
    run("standard-sheet-32.ron", "1", &out);
    let viewer = Viewer::start(&out);
    let k = 12;
    let result = self_test(&viewer.url, &dir.join("profile"), k);
    assert_eq!(result["frames"], 31);
    // The run's own per-frame series, plotted.
    assert_eq!(result["plots"], serde_json::json!(["kinetic energy", "self-intersections"]));
    assert_shows_obj(&result, &out.join(format!("sheet_{k}.obj")));
    let run_frame = obj_positions(&out.join(format!("sheet_{k}.obj")));
    // Frame k is not frame 1: the scrub moved the cloth.
    let first = obj_positions(&out.join("sheet_1.obj"));
    assert!((first[500][2] - run_frame[500][2]).abs() > 1e-3);
    screenshot(&viewer.url, &dir.join("profile"), 20, "sheet");
    viewer.interrupt();
    remove_test_dir(&dir);
}

#[test]
#[ignore = "needs chromium: cargo xtask test --viewer"]
fn viewer_shows_a_remeshed_cloths_changing_mesh() {
    let dir = temp_dir("remeshed");
    let out = dir.join("out");
    let status = anima()
        .args(["run", "--quiet", "--export", "gltf", "--duration", "0.3", "--out"])
        .arg(&out)
        .arg(scenes().join("../oliveira/test-2-table-adaptive.ron"))
        .status()
        .unwrap();
    assert!(status.success());
    let viewer = Viewer::start(&out);
    let profile = dir.join("profile");
    // Each frame is its own mesh: frame k shows cloth_k.obj's vertices, however many it has.
    for k in [1, 6] {
        let result = self_test(&viewer.url, &profile, k);
        assert_shows_obj(&result, &out.join(format!("cloth_{k}.obj")));
        let plots = ["kinetic energy", "self-intersections", "vertices", "contact responses (total)"];
        assert_eq!(result["plots"], serde_json::json!(plots));
    }
    viewer.interrupt();
    remove_test_dir(&dir);
}

#[test]
#[ignore = "needs chromium: cargo xtask test --viewer"]
fn viewer_plays_a_walk_and_shows_the_frame_scrubbed_to() {
    let dir = temp_dir("walk");
    let out = dir.join("out");
    run("walk.ron", "4", &out);
    // The walker's keyframes as the file holds them: the pelvis (the root link) is a child of the
    // figure's node, which does not move, so its translation track is its world position.
    let glb = std::fs::read(out.join("animation.glb")).unwrap();
    let gltf = gltf::Gltf::from_slice(&glb).unwrap();
    let blob = gltf.blob.as_deref();
    let animation = gltf.animations().next().expect("an animation");
    let pelvis = animation
        .channels()
        .find(|c| {
            c.target().node().name() == Some("pelvis")
                && c.target().property() == gltf::animation::Property::Translation
        })
        .expect("a translation track for the pelvis");
    let reader = pelvis.reader(|_| blob);
    let gltf::animation::util::ReadOutputs::Translations(track) = reader.read_outputs().unwrap() else {
        panic!("translations expected")
    };
    let track: Vec<[f32; 3]> = track.collect();
    let viewer = Viewer::start(&out);
    let k = 5;
    let result = self_test(&viewer.url, &dir.join("profile"), k);
    assert_eq!(result["frames"], track.len());
    let links = result["shown"]["links"].as_array().unwrap();
    assert_eq!(links.len(), 14, "the walker's 14 links");
    assert_eq!(result["plots"], serde_json::json!(["pelvis height", "pelvis speed", "contacts"]));
    let shown =
        links.iter().find(|l| l["name"] == "pelvis" && l["root"] == true).expect("the pelvis, a root");
    for a in 0..3 {
        let d = shown["position"][a].as_f64().unwrap() - f64::from(track[k][a]);
        assert!(
            d.abs() < 1e-6,
            "pelvis at frame {k}: page {} against the file {:?}",
            shown["position"],
            track[k]
        );
    }
    assert!((track[k][0] - track[0][0]).abs() > 0.1, "the walker moved by frame {k}");
    screenshot(&viewer.url, &dir.join("profile"), k, "walk");
    viewer.interrupt();
    remove_test_dir(&dir);
}

/// A process killed when dropped: a failing test leaves no `anima run --live` behind.
struct KilledOnDrop(Child);

impl Drop for KilledOnDrop {
    fn drop(&mut self) {
        let _ = self.0.kill();
        let _ = self.0.wait();
    }
}

/// `anima run --live` in Chromium: the live page loads without a console error, offers a slider per
/// controller parameter, and moving one changes the running controller at its next control step (the
/// run's note on the page, and the summary's `parameter_changes`).
#[test]
#[ignore = "needs chromium: cargo xtask test --viewer"]
fn viewer_live_slider_changes_the_running_controller() {
    let dir = temp_dir("live");
    let out = dir.join("out");
    let mut run = KilledOnDrop(
        anima()
            .args([
                "run",
                "--quiet",
                "--no-pictures",
                "--duration",
                "3",
                "--live",
                "--paused",
                "--port",
                "0",
                "--out",
            ])
            .arg(&out)
            .arg(scenes().join("walk.ron"))
            .stdout(Stdio::piped())
            .spawn()
            .unwrap(),
    );
    let mut line = String::new();
    BufReader::new(run.0.stdout.take().unwrap()).read_line(&mut line).unwrap();
    let url = line.split_whitespace().find(|w| w.starts_with("http://127.0.0.1:")).map(str::to_owned);
    let url = url.unwrap_or_else(|| panic!("no address in {line:?}"));
    let mut page = DevTools::start(&dir.join("profile"));
    page.call("Page.navigate", serde_json::json!({ "url": url }));
    let until = |page: &mut DevTools, expression: &str, what: &str| {
        let start = Instant::now();
        while page.evaluate(expression) != Value::Bool(true) {
            assert!(start.elapsed() < Duration::from_secs(60), "{what} in 60 s: {:?}", page.errors);
            std::thread::sleep(Duration::from_millis(200));
        }
    };
    until(&mut page, "window.anima?.ready === true && window.anima.frames > 0", "no parameters or frame");
    // The first slider moved to three quarters of its range, as a person drags it.
    let moved = page.evaluate(
        "(() => { const s = document.querySelector('#params input'); \
          s.value = Number(s.min) + 0.75 * (Number(s.max) - Number(s.min)); \
          s.dispatchEvent(new Event('change')); return [s.dataset.name, Number(s.value)]; })()",
    );
    let (name, value) = (moved[0].as_str().unwrap().to_owned(), moved[1].as_f64().unwrap());
    until(&mut page, "window.anima.changes.length === 1", "the run took no parameter");
    let change = page.evaluate("window.anima.changes[0]");
    assert_eq!(change["name"], name.as_str());
    assert_eq!(change["step"], 1);
    page.evaluate("document.getElementById('resume').click(), true");
    let status = wait(&mut run.0, Duration::from_secs(120)).expect("the live run did not end");
    assert!(status.success());
    assert_eq!(page.errors, Vec::<String>::new(), "console errors on the live page");
    let summary: Value = serde_json::from_slice(&std::fs::read(out.join("summary.json")).unwrap()).unwrap();
    let changes = summary["parameter_changes"].as_array().unwrap();
    assert_eq!(changes.len(), 1);
    assert!((changes[0]["value"].as_f64().unwrap() - value).abs() <= 0.5, "{changes:?} for {value}");
    drop(page);
    remove_test_dir(&dir);
}
