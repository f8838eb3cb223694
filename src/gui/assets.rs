//! The page, compiled into the binary: `page/index.html` with `page/style.css`
//! and `page/app.js` inlined and the run's token filled in, so one response
//! holds all of it (no network, no CDN, nothing read from disk).

use super::server::Reply;

const HTML: &str = include_str!("page/index.html");
const CSS: &str = include_str!("page/style.css");
const JS: &str = include_str!("page/app.js");

/// `GET /`: the page with its style, script and token.
pub fn page(token: &str) -> Reply {
    let body = HTML
        .replace("/*STYLE*/", CSS)
        .replace("/*SCRIPT*/", &JS.replace("__TOKEN__", token));
    Reply {
        status: 200,
        content_type: "text/html; charset=utf-8",
        body: body.into_bytes(),
    }
}
