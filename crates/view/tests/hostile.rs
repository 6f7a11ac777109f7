//! The viewer's server against hostile requests, on an ephemeral port: unknown paths, path traversal
//! in every spelling, other methods and hosts, huge request lines and headers. Each gets an HTTP
//! error, the server keeps serving, and the run's folder is left as it was.

use std::io::{Read, Write};
use std::net::{SocketAddr, TcpStream};
use std::path::{Path, PathBuf};
use std::time::Duration;

use anima_view::{Server, Stopper};

fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("anima-view-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// A folder as `anima run --export gltf` leaves it (the bytes need not be a real glTF here), and a
/// secret beside it that no request may reach.
fn run_folder(name: &str) -> PathBuf {
    let root = temp_dir(name);
    let dir = root.join("out");
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("animation.glb"), b"glTF fake").unwrap();
    std::fs::write(dir.join("summary.json"), b"{\"scene\":\"x\"}\n").unwrap();
    std::fs::write(dir.join("final.obj"), b"v 0 0 0\n").unwrap();
    std::fs::write(root.join("secret.txt"), b"secret").unwrap();
    dir
}

/// Every file under `dir` with its bytes, sorted.
fn snapshot(dir: &Path) -> Vec<(PathBuf, Vec<u8>)> {
    let mut files = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).unwrap() {
            let p = e.unwrap().path();
            if p.is_dir() {
                stack.push(p);
            } else {
                let bytes = std::fs::read(&p).unwrap();
                files.push((p, bytes));
            }
        }
    }
    files.sort();
    files
}

struct Running {
    addr: SocketAddr,
    stop: Stopper,
    thread: std::thread::JoinHandle<std::io::Result<()>>,
}

fn serve(dir: &Path) -> Running {
    let server = Server::bind(dir, 0).unwrap();
    let addr = server.local_addr();
    let stop = server.stopper();
    let thread = std::thread::spawn(move || server.run());
    Running { addr, stop, thread }
}

impl Running {
    fn end(self) {
        self.stop.stop();
        self.thread.join().expect("the server thread panicked").expect("the server failed");
    }
}

/// Sends `request` as raw bytes and returns the response's status code and the whole response.
fn send(addr: SocketAddr, request: &[u8]) -> (u16, String) {
    let mut s = TcpStream::connect(addr).unwrap();
    s.set_read_timeout(Some(Duration::from_secs(20))).unwrap();
    // The server may answer and close before it has read everything (a head too large): a broken
    // pipe on our side is then expected.
    let _ = s.write_all(request);
    let mut response = Vec::new();
    let _ = s.read_to_end(&mut response);
    let text = String::from_utf8_lossy(&response).into_owned();
    let status = text.split(' ').nth(1).and_then(|c| c.parse().ok()).unwrap_or_else(|| {
        panic!(
            "no HTTP status in the response to {:?}: {text:?}",
            String::from_utf8_lossy(&request[..60.min(request.len())])
        )
    });
    (status, text)
}

fn get(addr: SocketAddr, path: &str) -> (u16, String) {
    send(addr, format!("GET {path} HTTP/1.1\r\nHost: {addr}\r\nConnection: close\r\n\r\n").as_bytes())
}

/// The local files a page names in `href="/…"` or `src="/…"`.
fn local_references(page: &str) -> Vec<String> {
    let mut out = Vec::new();
    for key in ["href=\"/", "src=\"/"] {
        for (at, _) in page.match_indices(key) {
            let rest = &page[at + key.len() - 1..];
            out.push(rest[..rest.find('"').expect("a closing quote")].to_owned());
        }
    }
    out
}

#[test]
fn every_file_the_pages_name_is_served() {
    let dir = run_folder("references");
    let s = serve(&dir);
    // The player, and the live page (which a live server answers `/` with).
    for (page, script) in [("/", "/viewer.js"), ("/live.html", "/live.js")] {
        let (status, body) = get(s.addr, page);
        assert_eq!(status, 200, "{page}: {body}");
        let names = local_references(&body);
        assert!(
            names.iter().any(|n| n == "/page.css") && names.iter().any(|n| n == script),
            "{page}: {names:?}"
        );
        for name in names {
            let (status, body) = get(s.addr, &name);
            assert_eq!(status, 200, "{page} names {name}: {body}");
        }
    }
}

#[test]
fn serves_the_page_three_and_the_run() {
    let dir = run_folder("serves");
    let s = serve(&dir);
    let (status, page) = get(s.addr, "/");
    assert_eq!(status, 200, "{page}");
    assert!(page.contains("text/html") && page.contains("importmap"), "{page}");
    let (status, js) = get(s.addr, "/three/three.core.js");
    assert_eq!(status, 200);
    assert!(js.contains("text/javascript"));
    let (status, glb) = get(s.addr, "/run/animation.glb");
    assert_eq!(status, 200);
    assert!(glb.ends_with("glTF fake") && glb.contains("model/gltf-binary"), "{glb}");
    let (status, listing) = get(s.addr, "/run/");
    assert_eq!(status, 200);
    assert!(listing.ends_with("{\"files\":[\"animation.glb\",\"summary.json\"]}"), "{listing}");
    // The run wrote no series: a 404, not an empty file.
    assert_eq!(get(s.addr, "/run/series.json").0, 404);
    // HEAD answers like GET, without a body.
    let (status, head) = send(
        s.addr,
        format!("HEAD /run/summary.json HTTP/1.1\r\nHost: {}\r\nConnection: close\r\n\r\n", s.addr)
            .as_bytes(),
    );
    assert_eq!(status, 200);
    assert!(!head.contains("scene"), "{head}");
    s.end();
    std::fs::remove_dir_all(dir.parent().unwrap()).unwrap();
}

#[test]
fn hostile_requests_get_http_errors_and_leave_the_folder_unharmed() {
    let dir = run_folder("hostile");
    let root = dir.parent().unwrap().to_path_buf();
    let before = snapshot(&root);
    let s = serve(&dir);
    let a = s.addr;
    let not_found = [
        "/nothing",
        "/run/final.obj",
        "/run/../secret.txt",
        "/run/..%2fsecret.txt",
        "/run/%2e%2e/secret.txt",
        "/%2e%2e/%2e%2e/etc/passwd",
        "/../../etc/passwd",
        "/run/%2e%2e%2fsecret.txt",
        "/run//animation.glb",
        "/run/animation.glb/",
        "/run/animation.glb%00",
        "/run/ANIMATION.GLB",
        "/three/../../Cargo.toml",
        "/three/",
        "/index.html/..",
        "/run/%252e%252e/secret.txt",
        "/run/..\\secret.txt",
    ];
    for path in not_found {
        let (status, text) = get(a, path);
        assert_eq!(status, 404, "{path}: {text}");
        assert!(!text.contains("secret\u{0}") && !text.ends_with("secret"), "{path} leaked: {text}");
    }
    // Not a path at all, or not HTTP: 400.
    for request in [
        "GET ../../etc/passwd HTTP/1.1\r\nHost: x\r\n\r\n".as_bytes(),
        b"GET /\x00 HTTP/1.1\r\n\r\n",
        b"HELLO\r\n\r\n",
        b"GET / HTTP/9.9\r\n\r\n",
    ] {
        let (status, text) = send(a, request);
        assert!((400..500).contains(&status), "{:?}: {text}", String::from_utf8_lossy(request));
    }
    // Other methods.
    for method in ["POST", "PUT", "DELETE", "OPTIONS", "TRACE"] {
        let (status, text) = send(
            a,
            format!("{method} /run/animation.glb HTTP/1.1\r\nHost: {a}\r\nContent-Length: 0\r\nConnection: close\r\n\r\n")
                .as_bytes(),
        );
        assert_eq!(status, 405, "{method}: {text}");
    }
    // Another host (DNS rebinding), and none.
    let (status, _) = send(
        a,
        format!(
            "GET /run/summary.json HTTP/1.1\r\nHost: evil.example:{}\r\nConnection: close\r\n\r\n",
            a.port()
        )
        .as_bytes(),
    );
    assert_eq!(status, 403);
    let (status, _) = send(a, b"GET /run/summary.json HTTP/1.0\r\n\r\n");
    assert_eq!(status, 400);
    // A huge request line, a huge header, many headers: 431 (or 414 for a long path within the bound).
    let long_path = format!("/{}", "a".repeat(1 << 20));
    assert!((400..500).contains(&get(a, &long_path).0));
    let (status, _) = get(a, &format!("/{}", "a".repeat(4000)));
    assert_eq!(status, 414);
    let huge_header = format!("GET / HTTP/1.1\r\nHost: {a}\r\nX-Big: {}\r\n\r\n", "b".repeat(1 << 20));
    assert_eq!(send(a, huge_header.as_bytes()).0, 431);
    let many: String = (0..500).map(|i| format!("X-{i}: y\r\n")).collect();
    assert_eq!(send(a, format!("GET / HTTP/1.1\r\nHost: {a}\r\n{many}\r\n").as_bytes()).0, 431);
    // Still serving, and nothing changed on disk.
    assert_eq!(get(a, "/run/summary.json").0, 200);
    s.end();
    assert_eq!(snapshot(&root), before, "the folder changed");
    std::fs::remove_dir_all(&root).unwrap();
}

#[test]
fn a_folder_without_an_animation_is_refused_with_the_command_to_make_one() {
    let dir = temp_dir("empty");
    let e = Server::bind(&dir, 0).unwrap_err().to_string();
    assert!(e.contains("--export gltf"), "{e}");
    let e = Server::bind(&dir.join("missing"), 0).unwrap_err().to_string();
    assert!(e.contains("not a folder"), "{e}");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn it_listens_on_the_loopback_address_only() {
    let dir = run_folder("loopback");
    let server = Server::bind(&dir, 0).unwrap();
    assert!(server.local_addr().ip().is_loopback(), "{}", server.local_addr());
    // Stopped before it runs: run returns at once.
    server.stopper().stop();
    server.run().unwrap();
    std::fs::remove_dir_all(dir.parent().unwrap()).unwrap();
}
