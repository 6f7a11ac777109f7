//! `anima view`: a finished run in the browser. A small HTTP server, on the loopback address only,
//! serves one page that plays the run's `animation.glb` (the cloth or the figures with their
//! obstacles; play, pause, a timeline to scrub, an orbit camera) with plots of the run's per-frame
//! numbers beside it, and the run's `summary.json`.
//!
//! What this crate is not: it runs nothing and writes nothing. It reads what `anima run --export gltf`
//! left in a folder, and only the files it names ([`RUN_FILES`]); every other path is a 404 whatever
//! its spelling (`..`, `%2e%2e`, a long or odd one), because requests are matched against a fixed
//! table, never joined to a file system path.
//!
//! The page and three.js (r187, MIT, `assets/vendor/three/`) are embedded in the binary (`include_bytes!`),
//! so neither the build nor the page needs a network.
//!
//! Why hyper: it is the maintained HTTP/1 server that bounds a request's head (a head over
//! [`MAX_HEAD_BYTES`] or with more than 100 header lines gets a 431 before any of it reaches the
//! page's code) and times out a head that does not arrive ([`HEAD_TIMEOUT`]); tiny_http, lighter, reads
//! a request line or a header without bound and has no timeouts; axum adds routing this fixed table
//! does not need.
//!
//! A live run (`anima run SCENE --live`, [`Server::bind_live`]) adds one path, `/live`: a WebSocket,
//! an HTTP/1 upgrade of one of these connections (`hyper::upgrade::on`), spoken by tokio-tungstenite
//! on the same runtime; what the page may say, and the bounded channels between it and the run, are
//! in [`live`]. Why tokio-tungstenite: it is maintained, takes an upgraded hyper connection as it is
//! (`WebSocketStream::from_raw_socket`), bounds a message and a frame before buffering them
//! ([`MAX_MESSAGE_BYTES`]), and with only its `handshake` feature adds a handful of small pure-Rust
//! crates (tungstenite, sha1, data-encoding, rand; no TLS, no system library). fastwebsockets, the
//! other light option made for hyper, is faster on large messages, which a few words of commands
//! and one frame per message never are; its hyper upgrade helper (the `upgrade` feature) switches
//! hyper's client on as well, it leaves fragmented messages to a separate wrapper
//! (`FragmentCollector`), and its licence (Apache-2.0 only) is narrower than the workspace's. A hand-written RFC 6455 framer would be the kind of code this project does not write.
//!
//! ```no_run
//! let server = anima_view::Server::bind(std::path::Path::new("out/walk"), 0).unwrap();
//! println!("http://{}/", server.local_addr());
//! let stop = server.stopper(); // stop.stop() from a Ctrl-C handler ends run()
//! server.run().unwrap();
//! # drop(stop);
//! ```

mod assets;
pub mod live;
mod respond;
mod socket;

use std::net::{Ipv4Addr, SocketAddr};
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::Duration;

use hyper::server::conn::http1;
use hyper::service::service_fn;
use hyper_util::rt::{TokioIo, TokioTimer};
use tokio::sync::Notify;

pub use assets::RUN_FILES;
pub use socket::MAX_MESSAGE_BYTES;

/// The most bytes a request's head (request line and headers) may take; hyper answers 431 beyond.
pub const MAX_HEAD_BYTES: usize = 16 * 1024;

/// How long a connection may take to send a request's head.
pub const HEAD_TIMEOUT: Duration = Duration::from_secs(10);

/// Why a viewer could not start.
#[derive(Debug, thiserror::Error)]
pub enum ViewError {
    #[error("{0} is not a folder")]
    NotAFolder(PathBuf),
    #[error("{} has no animation.glb: run the scene with `anima run SCENE --out {} --export gltf`", .0.display(), .0.display())]
    NoAnimation(PathBuf),
    #[error("cannot listen on 127.0.0.1:{port}: {source}")]
    Bind { port: u16, source: std::io::Error },
    #[error("cannot start the server: {0}")]
    Runtime(std::io::Error),
}

/// What every request handler shares: the run's folder and where the server listens.
#[derive(Debug)]
struct Site {
    dir: PathBuf,
    addr: SocketAddr,
    /// A live run's parameters and channels (`anima run --live`); `None` for a finished run.
    live: Option<socket::LiveSite>,
}

/// What a live run gives the server: the parameters the page may set, the run's frames, and where
/// the page's commands go. See [`live`].
#[derive(Debug)]
pub struct Live {
    pub params: Vec<live::Param>,
    pub frames: live::FrameReceiver,
    pub commands: live::CommandSender,
}

/// A viewer bound to 127.0.0.1, not yet serving. [`Server::run`] serves until its [`Stopper`] is
/// called.
#[derive(Debug)]
pub struct Server {
    runtime: tokio::runtime::Runtime,
    listener: std::net::TcpListener,
    site: Arc<Site>,
    stop: Arc<Notify>,
}

/// Ends a [`Server::run`] from another thread (a Ctrl-C handler, a test). Stopping before `run` has
/// begun ends it as soon as it begins.
#[derive(Debug, Clone)]
pub struct Stopper(Arc<Notify>);

impl Stopper {
    pub fn stop(&self) {
        self.0.notify_one();
    }
}

impl Server {
    /// Binds 127.0.0.1:`port` (0: a free port, see [`Server::local_addr`]) to serve the run in `dir`,
    /// which must hold an `animation.glb`.
    pub fn bind(dir: &Path, port: u16) -> Result<Server, ViewError> {
        if !dir.is_dir() {
            return Err(ViewError::NotAFolder(dir.to_path_buf()));
        }
        if !dir.join("animation.glb").is_file() {
            return Err(ViewError::NoAnimation(dir.to_path_buf()));
        }
        Self::bind_inner(dir, port, None)
    }

    /// Binds 127.0.0.1:`port` for a run still going: the page's WebSocket at `/live` takes the run's
    /// frames and sends it commands; the run's folder `dir` is served as for a finished run, whatever
    /// it holds so far.
    pub fn bind_live(dir: &Path, port: u16, live: Live) -> Result<Server, ViewError> {
        if !dir.is_dir() {
            return Err(ViewError::NotAFolder(dir.to_path_buf()));
        }
        let Live { params, frames, commands } = live;
        let live = socket::LiveSite {
            params,
            frames: std::sync::Mutex::new(Some(frames)),
            commands,
            on_close: socket::OnClose::default(),
        };
        Self::bind_inner(dir, port, Some(live))
    }

    fn bind_inner(dir: &Path, port: u16, live: Option<socket::LiveSite>) -> Result<Server, ViewError> {
        let listener = std::net::TcpListener::bind((Ipv4Addr::LOCALHOST, port))
            .and_then(|l| l.set_nonblocking(true).map(|()| l))
            .map_err(|source| ViewError::Bind { port, source })?;
        let addr = listener.local_addr().map_err(|source| ViewError::Bind { port, source })?;
        let runtime = tokio::runtime::Builder::new_current_thread()
            .enable_io()
            .enable_time()
            .build()
            .map_err(ViewError::Runtime)?;
        Ok(Server {
            runtime,
            listener,
            site: Arc::new(Site { dir: dir.to_path_buf(), addr, live }),
            stop: Arc::new(Notify::new()),
        })
    }

    /// Where the server listens: 127.0.0.1 and its port.
    pub fn local_addr(&self) -> SocketAddr {
        self.site.addr
    }

    /// Calls `f` once, on the server's thread, when the first page that connected to `/live` goes away:
    /// it closed its socket, the connection dropped, or it broke the protocol. Not when the run's
    /// channels close (the run ended) or the server stops. A later call replaces an `f` not yet called;
    /// a server that is not live never calls it. `anima run --live --stop-with-page` stops the run
    /// from `f`.
    pub fn on_page_closed(&self, f: impl FnOnce() + Send + 'static) {
        if let Some(live) = &self.site.live
            && let Ok(mut slot) = live.on_close.0.lock()
        {
            *slot = Some(Box::new(f));
        }
    }

    /// A handle that ends [`Server::run`].
    pub fn stopper(&self) -> Stopper {
        Stopper(self.stop.clone())
    }

    /// Serves until stopped, on this thread (a task per connection: they are few, one browser's).
    /// Returns when the [`Stopper`] is called; connections still open are closed then.
    pub fn run(self) -> std::io::Result<()> {
        let Server { runtime, listener, site, stop } = self;
        runtime.block_on(async move {
            let listener = tokio::net::TcpListener::from_std(listener)?;
            let stopped = stop.notified();
            tokio::pin!(stopped);
            loop {
                tokio::select! {
                    () = &mut stopped => return Ok(()),
                    accepted = listener.accept() => match accepted {
                        Ok((stream, _)) => {
                            tokio::spawn(serve_connection(stream, site.clone()));
                        }
                        // Out of file descriptors and the like: wait a little rather than spin.
                        Err(_) => tokio::time::sleep(Duration::from_millis(50)).await,
                    },
                }
            }
        })
    }
}

/// One connection, request after request, with hyper's bounds on each request's head.
async fn serve_connection(stream: tokio::net::TcpStream, site: Arc<Site>) {
    let service = service_fn(move |request| {
        let site = site.clone();
        async move {
            if request.uri().path() == "/live" {
                return Ok::<_, std::convert::Infallible>(socket::upgrade(&site, request));
            }
            Ok(respond::respond(&site, &request).await)
        }
    });
    // A client that breaks the protocol or goes away ends its connection; nothing else to do.
    let _ = http1::Builder::new()
        .timer(TokioTimer::new())
        .header_read_timeout(HEAD_TIMEOUT)
        .max_buf_size(MAX_HEAD_BYTES)
        .serve_connection(TokioIo::new(stream), service)
        .with_upgrades()
        .await;
}
