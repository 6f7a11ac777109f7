//! What the server answers with: the pages, their style sheet and three.js, embedded, and the run's files, each at a
//! fixed path. Nothing else exists.

/// An embedded file: its path on the server, its media type and its bytes.
pub(crate) struct Embedded {
    pub path: &'static str,
    pub media_type: &'static str,
    pub bytes: &'static [u8],
}

const JS: &str = "text/javascript; charset=utf-8";

macro_rules! embed {
    ($path:literal, $media_type:expr, $file:literal) => {
        Embedded { path: $path, media_type: $media_type, bytes: include_bytes!(concat!("../assets/", $file)) }
    };
}

/// The page, its script and the parts of three.js it imports (through the page's import map).
pub(crate) const EMBEDDED: &[Embedded] = &[
    embed!("/", "text/html; charset=utf-8", "index.html"),
    embed!("/viewer.js", JS, "viewer.js"),
    // The layout the player and the live page share.
    embed!("/page.css", "text/css; charset=utf-8", "page.css"),
    // A live run's page (`anima run --live`), served at `/` in place of the player while the run goes.
    embed!("/live.html", "text/html; charset=utf-8", "live.html"),
    embed!("/live.js", JS, "live.js"),
    embed!("/three/three.module.js", JS, "vendor/three/three.module.js"),
    embed!("/three/three.core.js", JS, "vendor/three/three.core.js"),
    embed!("/three/addons/loaders/GLTFLoader.js", JS, "vendor/three/addons/loaders/GLTFLoader.js"),
    embed!(
        "/three/addons/utils/BufferGeometryUtils.js",
        JS,
        "vendor/three/addons/utils/BufferGeometryUtils.js"
    ),
    embed!("/three/addons/utils/SkeletonUtils.js", JS, "vendor/three/addons/utils/SkeletonUtils.js"),
    embed!("/three/addons/controls/OrbitControls.js", JS, "vendor/three/addons/controls/OrbitControls.js"),
    embed!("/three/LICENSE", "text/plain; charset=utf-8", "vendor/three/LICENSE"),
];

/// The run's files the page reads, served from the run's folder as `/run/<name>`, each with its media
/// type; `/run/` lists which of them the folder holds (JSON), so that the page asks only for those.
pub const RUN_FILES: &[(&str, &str)] = &[
    ("animation.glb", "model/gltf-binary"),
    ("summary.json", "application/json"),
    ("series.json", "application/json"),
];
