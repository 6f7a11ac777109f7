//! The `/live` WebSocket of a live run against a page that misbehaves, spoken byte by byte over a
//! plain TCP socket so that the test can send what no browser would: commands the run must not see
//! (unknown names, values out of range or not finite, binary), a frame header announcing a gigabyte,
//! an unmasked frame. Each gets an error message or a closed socket; the server keeps serving, a new
//! page can connect, the run receives only the valid commands, and the run's folder is untouched.

use std::io::{Read, Write};
use std::net::{SocketAddr, TcpStream};
use std::path::PathBuf;
use std::time::Duration;

use anima_view::live::{Command, CommandReceiver, Frame, FrameSender, Param, command_channel, frame_channel};
use anima_view::{Live, Server, Stopper};
use websocket::{frame, receive};

#[path = "support/websocket.rs"]
mod websocket;

fn run_folder(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("anima-view-live-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("summary.json"), b"{\"scene\":\"x\"}\n").unwrap();
    dir
}

struct Running {
    addr: SocketAddr,
    stop: Stopper,
    thread: std::thread::JoinHandle<std::io::Result<()>>,
    frames: FrameSender,
    commands: CommandReceiver,
}

fn serve_live(dir: &std::path::Path) -> Running {
    let (frames, frames_rx) = frame_channel();
    let (commands_tx, commands) = command_channel();
    let params = vec![Param { name: "swing_hip".into(), value: 0.5, min: -1.0, max: 1.0 }];
    let server =
        Server::bind_live(dir, 0, Live { params, frames: frames_rx, commands: commands_tx }).unwrap();
    let addr = server.local_addr();
    let stop = server.stopper();
    let thread = std::thread::spawn(move || server.run());
    Running { addr, stop, thread, frames, commands }
}

/// Opens `/live` and returns the socket after the 101, or the status of the refusal.
fn open(addr: SocketAddr, extra: &str) -> Result<TcpStream, u16> {
    let mut s = TcpStream::connect(addr).unwrap();
    s.set_read_timeout(Some(Duration::from_secs(20))).unwrap();
    let head = format!(
        "GET /live HTTP/1.1\r\nHost: {addr}\r\nUpgrade: websocket\r\nConnection: Upgrade\r\n\
         Sec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==\r\n{extra}\r\n"
    );
    s.write_all(head.as_bytes()).unwrap();
    // Read the response head byte by byte so as not to swallow the first WebSocket message.
    let mut response = Vec::new();
    let mut byte = [0u8];
    while !response.ends_with(b"\r\n\r\n") {
        if s.read(&mut byte).unwrap() == 0 {
            break;
        }
        response.push(byte[0]);
    }
    let text = String::from_utf8_lossy(&response).into_owned();
    let status: u16 = text.split(' ').nth(1).and_then(|c| c.parse().ok()).unwrap_or(0);
    if status != 101 {
        return Err(status);
    }
    // RFC 6455's example key and its accept value.
    assert!(text.contains("s3pPLMBiTxaQ9kYGzzhZRbK+xOo="), "{text}");
    Ok(s)
}

fn say(s: &mut TcpStream, text: &str) -> String {
    s.write_all(&frame(1, text.as_bytes(), true)).unwrap();
    let (opcode, payload) = receive(s).expect("the server closed the socket");
    assert_eq!(opcode, 1, "a text reply to {text:?}");
    String::from_utf8(payload).unwrap()
}

/// Whether the server closes the socket (a close frame, then the end) after what was sent.
fn closes(s: &mut TcpStream) -> bool {
    loop {
        match receive(s) {
            None | Some((8, _)) => return true,
            Some((1 | 2, _)) => continue,
            Some(_) => return false,
        }
    }
}

fn get_status(addr: SocketAddr, path: &str) -> u16 {
    let mut s = TcpStream::connect(addr).unwrap();
    s.set_read_timeout(Some(Duration::from_secs(20))).unwrap();
    write!(s, "GET {path} HTTP/1.1\r\nHost: {addr}\r\nConnection: close\r\n\r\n").unwrap();
    let mut response = String::new();
    let _ = s.read_to_string(&mut response);
    response.split(' ').nth(1).and_then(|c| c.parse().ok()).unwrap_or(0)
}

#[test]
fn live_socket_streams_frames_and_passes_checked_commands() {
    let dir = run_folder("stream");
    let before = std::fs::read(dir.join("summary.json")).unwrap();
    let mut live = serve_live(&dir);
    let mut s = open(live.addr, "Sec-WebSocket-Version: 13\r\n").unwrap();
    let (_, params) = receive(&mut s).unwrap();
    let params = String::from_utf8(params).unwrap();
    assert!(params.contains("\"name\":\"swing_hip\"") && params.contains("\"max\":1"), "{params}");

    assert_eq!(say(&mut s, "set swing_hip -0.25"), "ok set swing_hip -0.25");
    assert_eq!(say(&mut s, "pause"), "ok pause");
    for bad in ["set swing_hip NaN", "set swing_hip inf", "set swing_hip 2", "set knee 0", "jump", ""] {
        assert!(say(&mut s, bad).starts_with("error "), "{bad:?}");
    }
    s.write_all(&frame(2, &[1, 2, 3], true)).unwrap();
    let reply = receive(&mut s).map(|(o, p)| (o, String::from_utf8_lossy(&p).into_owned()));
    assert!(reply.as_ref().is_some_and(|(_, p)| p.starts_with("error ")), "{reply:?}");
    // Only the valid commands reached the run, in order.
    let got: Vec<Command> = live.commands.drain().collect();
    assert_eq!(got, vec![Command::Set { index: 0, value: -0.25 }, Command::Pause]);

    // A frame offered by the run arrives as a binary message.
    assert!(live.frames.offer(Frame { index: 7, time_s: 0.25, positions: vec![1.0, 2.0, 3.0] }));
    let (opcode, bytes) = receive(&mut s).unwrap();
    assert_eq!(opcode, 2);
    assert_eq!(bytes.len(), 4 + 8 + 12);
    assert_eq!(u32::from_le_bytes(bytes[0..4].try_into().unwrap()), 7);
    assert_eq!(f32::from_le_bytes(bytes[20..24].try_into().unwrap()), 3.0);

    // A note from the run arrives as a text message.
    assert!(live.frames.tell("{\"set\":1}".to_owned()));
    let (opcode, note) = receive(&mut s).unwrap();
    assert_eq!((opcode, note.as_slice()), (1, b"{\"set\":1}".as_slice()));

    // A second page while this one watches: refused.
    assert_eq!(open(live.addr, "Sec-WebSocket-Version: 13\r\n").unwrap_err(), 409);
    drop(s);
    assert_eq!(std::fs::read(dir.join("summary.json")).unwrap(), before);
    live.stop.stop();
    live.thread.join().unwrap().unwrap();
}

#[test]
fn live_socket_survives_huge_and_malformed_messages() {
    let dir = run_folder("hostile");
    let live = serve_live(&dir);
    assert_eq!(get_status(live.addr, "/live"), 426);
    assert_eq!(open(live.addr, "").unwrap_err(), 400, "no version");
    assert_eq!(open(live.addr, "Sec-WebSocket-Version: 8\r\n").unwrap_err(), 400);

    let hostile: Vec<Vec<u8>> = vec![
        // A frame header announcing a gigabyte, then a little of it.
        {
            let mut f = vec![0x81, 0x80 | 127];
            f.extend_from_slice(&(1u64 << 30).to_be_bytes());
            f.extend_from_slice(&[0; 4]);
            f.extend_from_slice(&[b'a'; 1000]);
            f
        },
        // A whole message over the bound.
        frame(1, &vec![b'a'; anima_view::MAX_MESSAGE_BYTES + 1], true),
        // Unmasked, which a client may not send.
        frame(1, b"pause", false),
        // Text that is not UTF-8.
        frame(1, &[0xff, 0xfe, 0xfd], true),
        // An opcode that does not exist.
        frame(3, b"x", true),
    ];
    for (k, bytes) in hostile.iter().enumerate() {
        // Each time a fresh page can connect: the last one gave the frames back when it closed.
        let mut s = open(live.addr, "Sec-WebSocket-Version: 13\r\n")
            .unwrap_or_else(|status| panic!("page {k} refused with {status}"));
        let _params = receive(&mut s).unwrap();
        let _ = s.write_all(bytes);
        assert!(closes(&mut s), "message {k} did not close the socket");
        // The socket task returns the frames before the next page asks; give it a moment.
        std::thread::sleep(Duration::from_millis(50));
    }
    assert_eq!(get_status(live.addr, "/"), 200);
    assert_eq!(live.commands.drain().count(), 0, "a hostile message reached the run");
    live.stop.stop();
    live.thread.join().unwrap().unwrap();
}

#[test]
fn a_finished_run_has_no_live_socket() {
    let dir = run_folder("finished");
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("animation.glb"), b"glTF fake").unwrap();
    let server = Server::bind(&dir, 0).unwrap();
    let addr = server.local_addr();
    let stop = server.stopper();
    let thread = std::thread::spawn(move || server.run());
    assert_eq!(get_status(addr, "/live"), 404);
    stop.stop();
    thread.join().unwrap().unwrap();
}
