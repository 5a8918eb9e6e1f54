//! The page and its scripts, embedded at build time from `web/` (three.js vendored into
//! `web/vendor/` by `cargo xtask vendor-web`), so serving needs no network and no file.

/// An embedded file.
pub struct Asset {
    pub content_type: &'static str,
    pub bytes: &'static [u8],
}

const HTML: &str = "text/html; charset=utf-8";
const JS: &str = "text/javascript; charset=utf-8";

/// The asset served at `path`, if any (exact match only).
pub fn find(path: &str) -> Option<Asset> {
    let (content_type, bytes): (&str, &[u8]) = match path {
        "/" | "/index.html" => (HTML, include_bytes!("../../web/index.html")),
        "/app.js" => (JS, include_bytes!("../../web/app.js")),
        "/three.module.js" => (JS, include_bytes!("../../web/vendor/three.module.min.js")),
        "/three.core.min.js" => (JS, include_bytes!("../../web/vendor/three.core.min.js")),
        "/OrbitControls.js" => (JS, include_bytes!("../../web/vendor/OrbitControls.js")),
        _ => return None,
    };
    Some(Asset {
        content_type,
        bytes,
    })
}
