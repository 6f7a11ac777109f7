//! One request, one response, never a panic: every path either names an embedded file or one of the
//! run's files, or gets an HTTP error.

use bytes::Bytes;
use http_body_util::Full;
use hyper::header::{self, HeaderValue};
use hyper::{Method, Request, Response, StatusCode};

use crate::Site;
use crate::assets::{EMBEDDED, RUN_FILES};

/// The longest path served; a longer one gets 414 (hyper has already bounded the whole head).
const MAX_PATH_BYTES: usize = 1024;

type Body = Full<Bytes>;

/// The response to `request`: the embedded page and scripts, the run's files under `/run/`, or an
/// error status with a one-line text body.
pub(crate) async fn respond<B>(site: &Site, request: &Request<B>) -> Response<Body> {
    if request.method() != Method::GET && request.method() != Method::HEAD {
        let mut r = error(StatusCode::METHOD_NOT_ALLOWED, "only GET and HEAD");
        r.headers_mut().insert(header::ALLOW, HeaderValue::from_static("GET, HEAD"));
        return r;
    }
    if let Some(status) = host_problem(site, request) {
        return error(status, "the viewer answers requests for 127.0.0.1 or localhost at its own port only");
    }
    let path = request.uri().path();
    if path.len() > MAX_PATH_BYTES {
        return error(StatusCode::URI_TOO_LONG, "path too long");
    }
    // A live run's page is its `/`: the player needs the animation the run writes only at its end.
    let path = if site.live.is_some() && path == "/" { "/live.html" } else { path };
    if let Some(e) = EMBEDDED.iter().find(|e| e.path == path || (e.path == "/" && path == "/index.html")) {
        return ok(e.media_type, Bytes::from_static(e.bytes));
    }
    if path == "/run/" {
        return ok("application/json", Bytes::from(listing(site).await));
    }
    let Some(&(name, media_type)) =
        path.strip_prefix("/run/").and_then(|n| RUN_FILES.iter().find(|f| f.0 == n))
    else {
        return error(StatusCode::NOT_FOUND, "not found");
    };
    let file = site.dir.join(name);
    match tokio::fs::metadata(&file).await {
        Ok(m) if m.is_file() => {}
        Ok(_) => return error(StatusCode::NOT_FOUND, "not a file"),
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
            return error(StatusCode::NOT_FOUND, "not found");
        }
        Err(_) => return error(StatusCode::INTERNAL_SERVER_ERROR, "cannot read the run's file"),
    }
    match tokio::fs::read(&file).await {
        Ok(bytes) => ok(media_type, Bytes::from(bytes)),
        Err(_) => error(StatusCode::INTERNAL_SERVER_ERROR, "cannot read the run's file"),
    }
}

/// Refuses a request whose `Host` is not this server (400 without one, 403 for another): a page on
/// another site that a DNS name rebound to 127.0.0.1 cannot read the run.
pub(crate) fn host_problem<B>(site: &Site, request: &Request<B>) -> Option<StatusCode> {
    let Some(host) = request.headers().get(header::HOST).and_then(|h| h.to_str().ok()) else {
        return Some(StatusCode::BAD_REQUEST);
    };
    let port = site.addr.port();
    let ours = host == format!("127.0.0.1:{port}") || host == format!("localhost:{port}");
    (!ours).then_some(StatusCode::FORBIDDEN)
}

/// `{"files":[…]}`: which of [`RUN_FILES`] the run's folder holds.
async fn listing(site: &Site) -> String {
    let mut present = Vec::new();
    for (name, _) in RUN_FILES {
        if tokio::fs::metadata(site.dir.join(name)).await.is_ok_and(|m| m.is_file()) {
            present.push(format!("\"{name}\""));
        }
    }
    format!("{{\"files\":[{}]}}", present.join(","))
}

fn ok(media_type: &'static str, body: Bytes) -> Response<Body> {
    let mut r = Response::new(Full::new(body));
    let h = r.headers_mut();
    h.insert(header::CONTENT_TYPE, HeaderValue::from_static(media_type));
    // The run's files change when the run is repeated; the page must not show an old one.
    h.insert(header::CACHE_CONTROL, HeaderValue::from_static("no-store"));
    h.insert(header::X_CONTENT_TYPE_OPTIONS, HeaderValue::from_static("nosniff"));
    r
}

fn error(status: StatusCode, why: &'static str) -> Response<Body> {
    let mut r = ok("text/plain; charset=utf-8", Bytes::from_static(why.as_bytes()));
    *r.status_mut() = status;
    r
}
