//! `/live`: the WebSocket of `anima run SCENE --live`, an HTTP/1 upgrade of one of hyper's
//! connections, spoken by tokio-tungstenite on the same one-thread runtime.
//!
//! Messages from the page are bounded ([`MAX_MESSAGE_BYTES`]; tungstenite refuses a longer frame or
//! message before buffering it, and the socket closes); a text message is a command
//! ([`crate::live::Command::parse`]) and gets `ok …` or `error …` back; anything else gets `error …`.
//! Frames go out as binary messages ([`crate::live::Frame::to_bytes`]). One page at a time receives
//! frames: a second socket while one is open is refused with 409, since frames are not copied.

use std::sync::{Arc, Mutex};

use bytes::Bytes;
use futures_util::{SinkExt, StreamExt};
use http_body_util::Full;
use hyper::header::{self, HeaderValue};
use hyper::{Request, Response, StatusCode};
use hyper_util::rt::TokioIo;
use tokio_tungstenite::WebSocketStream;
use tokio_tungstenite::tungstenite::Message;
use tokio_tungstenite::tungstenite::handshake::derive_accept_key;
use tokio_tungstenite::tungstenite::protocol::{Role, WebSocketConfig};

use crate::Site;
use crate::live::{Command, CommandSender, FrameReceiver, Param, params_json};

/// The longest message (and frame) a page may send; commands are a few words.
pub const MAX_MESSAGE_BYTES: usize = 4096;

/// What the server holds of a live run.
#[derive(Debug)]
pub(crate) struct LiveSite {
    pub params: Vec<Param>,
    /// Taken by the open socket, put back when it closes.
    pub frames: Mutex<Option<FrameReceiver>>,
    pub commands: CommandSender,
    /// Called once, when the first page that connected closes its socket ([`crate::Server::on_page_closed`]).
    pub on_close: OnClose,
}

/// What to do when a page goes away: nothing until [`crate::Server::on_page_closed`] sets it.
#[derive(Default)]
pub(crate) struct OnClose(pub Mutex<Option<Box<dyn FnOnce() + Send>>>);

impl std::fmt::Debug for OnClose {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let set = self.0.lock().is_ok_and(|c| c.is_some());
        f.write_str(if set { "OnClose(set)" } else { "OnClose(none)" })
    }
}

/// The answer to a request for `/live`: 101 and a socket task, or an HTTP error.
pub(crate) fn upgrade<B>(site: &Arc<Site>, mut request: Request<B>) -> Response<Full<Bytes>>
where
    B: Send + 'static,
{
    let Some(live) = &site.live else {
        return error(StatusCode::NOT_FOUND, "not a live run");
    };
    if let Some(status) = crate::respond::host_problem(site, &request) {
        return error(status, "the viewer answers requests for 127.0.0.1 or localhost at its own port only");
    }
    let headers = request.headers();
    let says = |name: header::HeaderName, word: &str| {
        headers
            .get_all(name)
            .iter()
            .filter_map(|v| v.to_str().ok())
            .any(|v| v.split(',').any(|w| w.trim().eq_ignore_ascii_case(word)))
    };
    if !says(header::UPGRADE, "websocket") || !says(header::CONNECTION, "upgrade") {
        return error(StatusCode::UPGRADE_REQUIRED, "/live is a WebSocket");
    }
    if headers.get(header::SEC_WEBSOCKET_VERSION).is_none_or(|v| v != "13") {
        return error(StatusCode::BAD_REQUEST, "WebSocket version 13 only");
    }
    let Some(key) = headers.get(header::SEC_WEBSOCKET_KEY) else {
        return error(StatusCode::BAD_REQUEST, "no Sec-WebSocket-Key");
    };
    let accept = derive_accept_key(key.as_bytes());
    let Some(frames) = live.frames.lock().ok().and_then(|mut f| f.take()) else {
        return error(StatusCode::CONFLICT, "another page is watching this run");
    };
    let on_upgrade = hyper::upgrade::on(&mut request);
    let site = site.clone();
    tokio::spawn(async move {
        let mut frames = frames;
        if let Ok(upgraded) = on_upgrade.await {
            let config = WebSocketConfig::default()
                .max_message_size(Some(MAX_MESSAGE_BYTES))
                .max_frame_size(Some(MAX_MESSAGE_BYTES));
            let ws =
                WebSocketStream::from_raw_socket(TokioIo::new(upgraded), Role::Server, Some(config)).await;
            if let Some(live) = &site.live
                && serve_socket(ws, live, &mut frames).await == Ended::PageGone
                && let Some(on_close) = live.on_close.0.lock().ok().and_then(|mut c| c.take())
            {
                on_close();
            }
        }
        if let Some(live) = &site.live
            && let Ok(mut slot) = live.frames.lock()
        {
            *slot = Some(frames);
        }
    });
    let mut r = Response::new(Full::new(Bytes::new()));
    *r.status_mut() = StatusCode::SWITCHING_PROTOCOLS;
    let h = r.headers_mut();
    h.insert(header::UPGRADE, HeaderValue::from_static("websocket"));
    h.insert(header::CONNECTION, HeaderValue::from_static("Upgrade"));
    if let Ok(v) = HeaderValue::from_str(&accept) {
        h.insert(header::SEC_WEBSOCKET_ACCEPT, v);
    }
    r
}

/// Why a socket ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Ended {
    /// The page closed it, the connection dropped, or the page broke the protocol.
    PageGone,
    /// The run's channels closed: the run is over.
    RunGone,
}

/// The page's commands in, the run's frames out, until either side goes away or the page breaks
/// the protocol.
async fn serve_socket<S>(mut ws: WebSocketStream<S>, live: &LiveSite, frames: &mut FrameReceiver) -> Ended
where
    S: tokio::io::AsyncRead + tokio::io::AsyncWrite + Unpin,
{
    if ws.send(Message::text(params_json(&live.params))).await.is_err() {
        return Ended::PageGone;
    }
    loop {
        // Biased, notes before frames: the run tells the page what to draw (`{"mesh":…}`) before the
        // frame that needs it, and both wait in their channels until a page connects; an unbiased
        // select sent a paused run's first frame before its mesh half the time, and the page, with no
        // mesh to put the points on, showed nothing until the run went on.
        tokio::select! {
            biased;
            incoming = ws.next() => {
                let reply = match incoming {
                    Some(Ok(Message::Text(text))) => answer(live, text.as_str()),
                    Some(Ok(Message::Binary(_))) => "error send commands as text".to_owned(),
                    Some(Ok(Message::Ping(_) | Message::Pong(_) | Message::Frame(_))) => continue,
                    // Closed, gone, or broke the protocol (too long, malformed): this socket ends.
                    Some(Ok(Message::Close(_)) | Err(_)) | None => return Ended::PageGone,
                };
                if ws.send(Message::text(reply)).await.is_err() {
                    return Ended::PageGone;
                }
            }
            note = frames.1.recv() => {
                let Some(note) = note else { return Ended::RunGone };
                if ws.send(Message::text(note)).await.is_err() {
                    return Ended::PageGone;
                }
            }
            frame = frames.0.recv() => {
                let Some(frame) = frame else { return Ended::RunGone };
                if ws.send(Message::binary(frame.to_bytes())).await.is_err() {
                    return Ended::PageGone;
                }
            }
        }
    }
}

/// `ok COMMAND` when the command went to the run, `error WHY` otherwise.
fn answer(live: &LiveSite, text: &str) -> String {
    match Command::parse(text, &live.params).and_then(|c| live.commands.send(c)) {
        Ok(()) => format!("ok {}", text.trim()),
        Err(why) => format!("error {why}"),
    }
}

fn error(status: StatusCode, why: &'static str) -> Response<Full<Bytes>> {
    let mut r = Response::new(Full::new(Bytes::from_static(why.as_bytes())));
    *r.status_mut() = status;
    r.headers_mut().insert(header::CONTENT_TYPE, HeaderValue::from_static("text/plain; charset=utf-8"));
    r
}
