//! `anima run SCENE --live` driven through its WebSocket as a page would, byte by byte over a plain
//! TCP socket: a walk started paused, a controller parameter set from the page and seen taken by the
//! running controller (the run's note, and the summary's `parameter_changes`), values the page may not
//! send (out of range, not finite, an unknown name) refused with the run and its folder unharmed.

use std::io::{BufRead, BufReader, Read, Write};
use std::net::TcpStream;
use std::path::Path;
use std::process::{Command, Stdio};
use std::time::Duration;

use serde_json::Value;
use websocket::{frame, receive};

#[path = "../../view/tests/support/websocket.rs"]
mod websocket;

/// The next text message, frames skipped.
fn next_text(s: &mut TcpStream) -> String {
    loop {
        match receive(s).expect("the socket closed") {
            (1, p) => return String::from_utf8(p).unwrap(),
            (2, _) => continue,
            (op, _) => panic!("opcode {op}"),
        }
    }
}

/// Sends a command and returns the server's reply (`ok …` or `error …`), keeping the notes passed.
fn say(s: &mut TcpStream, text: &str, notes: &mut Vec<String>) -> String {
    s.write_all(&frame(1, text.as_bytes(), true)).unwrap();
    loop {
        let t = next_text(s);
        if t.starts_with("ok ") || t.starts_with("error ") {
            return t;
        }
        notes.push(t);
    }
}

#[test]
fn a_slider_moved_on_the_live_page_changes_the_running_controller() {
    let out = std::env::temp_dir().join(format!("anima-live-cli-{}", std::process::id()));
    let (mut child, addr) = start_paused_walk(&out, &[]);
    let (mut s, params) = open_live(&addr);
    let params = params["params"].as_array().unwrap();
    assert!(!params.is_empty(), "a walker's controller offers its parameters");
    let p = &params[0];
    let name = p["name"].as_str().unwrap().to_owned();
    let (min, max, value) =
        (p["min"].as_f64().unwrap(), p["max"].as_f64().unwrap(), p["value"].as_f64().unwrap());
    let new =
        value + 0.25 * (max - value).max(value - min) * if max - value > value - min { 1.0 } else { -1.0 };

    let mut notes = Vec::new();
    assert_eq!(say(&mut s, &format!("set {name} {new}"), &mut notes), format!("ok set {name} {new}"));
    for bad in [
        format!("set {name} NaN"),
        format!("set {name} inf"),
        format!("set {name} {}", max + 1.0),
        format!("set {name} {}", min - 1.0),
        "set no-such-parameter 0".to_owned(),
        format!("set {name}"),
    ] {
        let reply = say(&mut s, &bad, &mut notes);
        assert!(reply.starts_with("error "), "{bad:?} gave {reply:?}");
    }
    assert_eq!(say(&mut s, "resume", &mut notes), "ok resume");
    // The run's notes until it ends: the change taken at the first control step, then the end.
    while let Some((op, payload)) = receive(&mut s) {
        if op == 1 {
            notes.push(String::from_utf8(payload).unwrap());
        }
        if op == 8 || notes.last().is_some_and(|n| n.starts_with("{\"done\"")) {
            break;
        }
    }
    let set = notes.iter().find(|n| n.starts_with("{\"set\"")).unwrap_or_else(|| panic!("{notes:?}"));
    let set: Value = serde_json::from_str(set).unwrap();
    assert_eq!(set["set"]["name"], name.as_str());
    assert_eq!(set["set"]["step"], 1);
    assert!(notes.iter().all(|n| !n.starts_with("{\"refused\"")), "{notes:?}");
    assert!(notes.iter().any(|n| n.starts_with("{\"done\"")), "{notes:?}");

    assert!(child.0.wait().unwrap().success());
    let summary: Value = serde_json::from_slice(&std::fs::read(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["steps"], 60, "{summary}");
    assert!(summary["error"].is_null(), "{summary}");
    let changes = summary["parameter_changes"].as_array().unwrap();
    assert_eq!(changes.len(), 1, "only the valid value reached the controller: {changes:?}");
    assert_eq!(changes[0]["name"], name.as_str());
    // The value the controller holds: the page's, rounded for a whole-iteration kind.
    let held = changes[0]["value"].as_f64().unwrap();
    assert_eq!(held, set["set"]["value"].as_f64().unwrap());
    assert!((held - new).abs() <= 0.5 && held != value, "{held} for {new}");
    // The folder holds the run's outputs, whole: no temporary left behind.
    for entry in std::fs::read_dir(&out).unwrap() {
        let name = entry.unwrap().file_name().into_string().unwrap();
        assert!(!name.contains(".tmp"), "{name} left in the output folder");
    }
    std::fs::remove_dir_all(&out).unwrap();
}

/// The child killed (and reaped) when the test ends, however it ends.
struct KillOnDrop(std::process::Child);

impl Drop for KillOnDrop {
    fn drop(&mut self) {
        let _ = self.0.kill();
        let _ = self.0.wait();
    }
}

/// A paused live walk into `out` with `extra` flags, and the address it prints.
fn start_paused_walk(out: &Path, extra: &[&str]) -> (KillOnDrop, String) {
    let _ = std::fs::remove_dir_all(out);
    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets/scenes/walk.ron");
    let child = Command::new(env!("CARGO_BIN_EXE_anima"))
        .args(["run", "--quiet", "--no-pictures", "--duration", "3", "--live", "--paused", "--port", "0"])
        .args(extra)
        .arg("--out")
        .arg(out)
        .arg(&scene)
        .stdout(Stdio::piped())
        .spawn()
        .unwrap();
    let mut child = KillOnDrop(child);
    let mut line = String::new();
    BufReader::new(child.0.stdout.take().unwrap()).read_line(&mut line).unwrap();
    let addr = line
        .split_whitespace()
        .find_map(|w| w.strip_prefix("http://"))
        .map(|a| a.trim_end_matches('/').to_owned())
        .unwrap_or_else(|| panic!("no address in {line:?}"));
    (child, addr)
}

/// A WebSocket on `/live`, and the parameters message it opens with.
fn open_live(addr: &str) -> (TcpStream, Value) {
    let mut s = TcpStream::connect(addr).unwrap();
    s.set_read_timeout(Some(Duration::from_secs(60))).unwrap();
    write!(
        s,
        "GET /live HTTP/1.1\r\nHost: {addr}\r\nUpgrade: websocket\r\nConnection: Upgrade\r\n\
         Sec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==\r\nSec-WebSocket-Version: 13\r\n\r\n"
    )
    .unwrap();
    let mut response = Vec::new();
    let mut byte = [0u8];
    while !response.ends_with(b"\r\n\r\n") {
        assert_eq!(s.read(&mut byte).unwrap(), 1, "the server closed during the handshake");
        response.push(byte[0]);
    }
    assert!(response.starts_with(b"HTTP/1.1 101"), "{}", String::from_utf8_lossy(&response));
    let params: Value = serde_json::from_str(&next_text(&mut s)).unwrap();
    assert!(params["params"].is_array(), "{params}");
    (s, params)
}

/// The child's exit status once it exits, `None` if it still runs after `within`.
fn exits_within(child: &mut KillOnDrop, within: Duration) -> Option<std::process::ExitStatus> {
    let start = std::time::Instant::now();
    while start.elapsed() < within {
        if let Some(status) = child.0.try_wait().unwrap() {
            return Some(status);
        }
        std::thread::sleep(Duration::from_millis(50));
    }
    None
}

/// The output folder holds no temporary: every file is whole.
fn assert_whole(out: &Path) {
    for entry in std::fs::read_dir(out).unwrap() {
        let name = entry.unwrap().file_name().into_string().unwrap();
        assert!(!name.contains(".tmp"), "{name} left in the output folder");
    }
}

#[test]
fn with_stop_with_page_the_run_ends_when_the_page_closes() {
    // A close frame, then a connection that just drops: either ends the run as Ctrl-C does.
    for (i, polite) in [true, false].into_iter().enumerate() {
        let out = std::env::temp_dir().join(format!("anima-live-stop-{}-{i}", std::process::id()));
        let (mut child, addr) = start_paused_walk(&out, &["--stop-with-page"]);
        let (mut s, _) = open_live(&addr);
        if polite {
            s.write_all(&frame(8, &1000u16.to_be_bytes(), true)).unwrap();
        }
        drop(s);
        let status = exits_within(&mut child, Duration::from_secs(10))
            .unwrap_or_else(|| panic!("the run went on after the page closed (close frame: {polite})"));
        assert_eq!(status.code(), Some(130), "an interrupted run's status");
        assert!(out.is_dir());
        assert_whole(&out);
        assert!(!out.join("summary.json").exists(), "an interrupted run writes no summary");
        std::fs::remove_dir_all(&out).unwrap();
    }
}

#[test]
fn without_stop_with_page_the_run_outlives_its_page() {
    let out = std::env::temp_dir().join(format!("anima-live-stay-{}", std::process::id()));
    let (mut child, addr) = start_paused_walk(&out, &[]);
    let (mut s, _) = open_live(&addr);
    s.write_all(&frame(8, &1000u16.to_be_bytes(), true)).unwrap();
    drop(s);
    assert!(exits_within(&mut child, Duration::from_secs(2)).is_none(), "the run ended with its page");
    // Another page may watch it still.
    drop(open_live(&addr));
    drop(child);
    let _ = std::fs::remove_dir_all(&out);
}
