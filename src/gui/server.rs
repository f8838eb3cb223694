//! The HTTP side: binding 127.0.0.1, the security checks every request passes
//! (Host, Origin, per-run token), bounded bodies, routing and JSON replies.
//!
//! Rules: listen on loopback only; every request carries the random token
//! (query `token=` or header `X-Sweepmtf-Token`); a Host other than the served
//! `127.0.0.1:PORT`, or an Origin other than `http://127.0.0.1:PORT`, is
//! refused (DNS rebinding, cross-site requests); bodies are bounded.

use super::session::Session;
use super::{GuiConfig, GuiError, assets, batch_api, charts_api, magnify, measure_api, model_api};
use serde_json::{Value, json};
use std::io::{Cursor, Read};
use std::sync::Mutex;

/// Largest photo upload accepted (bytes).
pub const MAX_UPLOAD_BYTES: u64 = 400 << 20;
/// Largest JSON request body accepted (bytes).
pub const MAX_BODY_BYTES: u64 = 1 << 20;
/// The header that may carry the token instead of the query.
pub const TOKEN_HEADER: &str = "X-Sweepmtf-Token";

/// A reply: status, content type, body.
pub struct Reply {
    /// HTTP status.
    pub status: u16,
    /// Content-Type.
    pub content_type: &'static str,
    /// Body bytes.
    pub body: Vec<u8>,
}

impl Reply {
    /// 200 with a JSON body.
    pub fn json(v: &Value) -> Reply {
        Reply {
            status: 200,
            content_type: "application/json",
            body: v.to_string().into_bytes(),
        }
    }
    /// An error as JSON `{"error": message, "code": exit code}` (the CLI's message and code).
    pub fn error(status: u16, code: u8, message: impl Into<String>) -> Reply {
        Reply {
            status,
            content_type: "application/json",
            body: json!({ "error": message.into(), "code": code })
                .to_string()
                .into_bytes(),
        }
    }
    /// An error from the CLI's error type (HTTP 422, 400 for usage errors).
    pub fn cli(e: crate::cli::CliError) -> Reply {
        let status = if e.code == crate::cli::Code::Usage {
            400
        } else {
            422
        };
        Reply::error(status, e.code as u8, e.message)
    }
}

/// The running server's shared state.
pub struct Server {
    /// The listener.
    pub http: tiny_http::Server,
    /// The per-run token (32 hex digits).
    pub token: String,
    /// The port bound.
    pub port: u16,
    /// Photos, targets, output folder.
    pub session: Mutex<Session>,
}

fn random_token() -> Result<String, GuiError> {
    let mut b = [0u8; 16];
    getrandom::fill(&mut b).map_err(|e| GuiError::Random(e.to_string()))?;
    Ok(b.iter().map(|x| format!("{x:02x}")).collect())
}

impl Server {
    /// Opens the named files and binds 127.0.0.1:`config.port`.
    pub fn bind(config: GuiConfig) -> Result<Server, GuiError> {
        let session = Session::open(&config)?;
        let http =
            tiny_http::Server::http(("127.0.0.1", config.port)).map_err(|e| GuiError::Listen {
                port: config.port,
                cause: e.to_string(),
            })?;
        let port = http
            .server_addr()
            .to_ip()
            .map(|a| a.port())
            .ok_or_else(|| GuiError::Listen {
                port: config.port,
                cause: "not an IP socket".into(),
            })?;
        Ok(Server {
            http,
            token: random_token()?,
            port,
            session: Mutex::new(session),
        })
    }

    /// Answers requests until unblocked.
    pub fn serve(&self) {
        while let Ok(mut req) = self.http.recv() {
            let reply = self.answer(&mut req);
            let _ = req.respond(to_response(reply));
        }
    }

    fn answer(&self, req: &mut tiny_http::Request) -> Reply {
        let url = req.url().to_string();
        let (path, query) = url.split_once('?').unwrap_or((&url, ""));
        let query = parse_query(query);
        if let Err(why) = self.check(req, &query) {
            return Reply::error(403, 2, why);
        }
        let get = *req.method() == tiny_http::Method::Get;
        let post = *req.method() == tiny_http::Method::Post;
        let q = |k: &str| query.iter().find(|(n, _)| n == k).map(|(_, v)| v.as_str());
        match (path, get, post) {
            ("/", true, _) => assets::page(&self.token),
            ("/api/state", true, _) => measure_api::state(self),
            ("/api/display", true, _) => measure_api::display(self, q("id")),
            ("/api/crop", true, _) => magnify::endpoint(self, q("id"), q("x"), q("y")),
            ("/api/charts", true, _) => charts_api::endpoint(self, q("id"), q("target")),
            ("/api/batch", true, _) => batch_api::table(q("dir")),
            ("/api/batch/file", true, _) => batch_api::file(q("dir"), q("name")),
            ("/api/upload", _, true) => match read_body(req, MAX_UPLOAD_BYTES) {
                Ok(b) => measure_api::upload(self, q("name").unwrap_or("upload"), b),
                Err(r) => r,
            },
            ("/api/measure", _, true) => match read_json(req) {
                Ok(v) => measure_api::measure(self, v),
                Err(r) => r,
            },
            ("/api/save", _, true) => match read_json(req) {
                Ok(v) => measure_api::save(self, v),
                Err(r) => r,
            },
            ("/api/model", _, true) => match read_json(req) {
                Ok(v) => model_api::model(v),
                Err(r) => r,
            },
            _ => Reply::error(404, 2, format!("no such page: {path}")),
        }
    }

    /// The security checks: Host, Origin, token.
    fn check(&self, req: &tiny_http::Request, query: &[(String, String)]) -> Result<(), String> {
        let header = |name: &str| {
            req.headers()
                .iter()
                .find(|h| h.field.to_string().eq_ignore_ascii_case(name))
                .map(|h| h.value.as_str().to_string())
        };
        let host = format!("127.0.0.1:{}", self.port);
        match header("Host") {
            Some(h) if h == host => {}
            Some(h) => return Err(format!("refused: Host '{h}' is not {host}")),
            None => return Err("refused: no Host header".into()),
        }
        if let Some(o) = header("Origin")
            && o != format!("http://{host}")
        {
            return Err(format!("refused: Origin '{o}' is not http://{host}"));
        }
        let given = header(TOKEN_HEADER).or_else(|| {
            query
                .iter()
                .find(|(k, _)| k == "token")
                .map(|(_, v)| v.clone())
        });
        match given {
            Some(t) if same(t.as_bytes(), self.token.as_bytes()) => Ok(()),
            Some(_) => Err("refused: wrong token".into()),
            None => Err("refused: no token (open the URL sweepmtf gui printed)".into()),
        }
    }
}

/// Constant-time comparison (the token is a secret).
fn same(a: &[u8], b: &[u8]) -> bool {
    a.len() == b.len() && a.iter().zip(b).fold(0u8, |acc, (x, y)| acc | (x ^ y)) == 0
}

fn to_response(r: Reply) -> tiny_http::Response<Cursor<Vec<u8>>> {
    let h = |k: &str, v: &str| {
        tiny_http::Header::from_bytes(k.as_bytes(), v.as_bytes()).expect("static header")
    };
    tiny_http::Response::from_data(r.body)
        .with_status_code(r.status)
        .with_header(h("Content-Type", r.content_type))
        .with_header(h("Cache-Control", "no-store"))
        .with_header(h("X-Content-Type-Options", "nosniff"))
        .with_header(h("Referrer-Policy", "no-referrer"))
        .with_header(h("X-Frame-Options", "DENY"))
        .with_header(h(
            "Content-Security-Policy",
            "default-src 'none'; script-src 'unsafe-inline'; style-src 'unsafe-inline'; \
             img-src 'self' data:; connect-src 'self'; frame-ancestors 'none'",
        ))
}

/// Reads a body of at most `limit` bytes (413 beyond).
fn read_body(req: &mut tiny_http::Request, limit: u64) -> Result<Vec<u8>, Reply> {
    let too_big = || {
        Reply::error(
            413,
            3,
            format!("upload too large: the limit is {} MiB", limit >> 20),
        )
    };
    if req.body_length().is_some_and(|n| n as u64 > limit) {
        return Err(too_big());
    }
    let mut buf = Vec::new();
    req.as_reader()
        .take(limit + 1)
        .read_to_end(&mut buf)
        .map_err(|e| Reply::error(400, 3, format!("cannot read the request: {e}")))?;
    if buf.len() as u64 > limit {
        return Err(too_big());
    }
    Ok(buf)
}

fn read_json(req: &mut tiny_http::Request) -> Result<Value, Reply> {
    let body = read_body(req, MAX_BODY_BYTES)?;
    serde_json::from_slice(&body)
        .map_err(|e| Reply::error(400, 2, format!("the request is not JSON: {e}")))
}

/// `a=b&c=d` with percent-decoding.
fn parse_query(q: &str) -> Vec<(String, String)> {
    q.split('&')
        .filter(|p| !p.is_empty())
        .map(|p| {
            let (k, v) = p.split_once('=').unwrap_or((p, ""));
            (percent_decode(k), percent_decode(v))
        })
        .collect()
}

fn percent_decode(s: &str) -> String {
    let b = s.as_bytes();
    let mut out = Vec::with_capacity(b.len());
    let mut i = 0;
    while i < b.len() {
        let hex = |c: u8| (c as char).to_digit(16);
        match b[i] {
            b'%' if i + 2 < b.len() => match (hex(b[i + 1]), hex(b[i + 2])) {
                (Some(h), Some(l)) => {
                    out.push((h * 16 + l) as u8);
                    i += 3;
                    continue;
                }
                _ => out.push(b'%'),
            },
            b'+' => out.push(b' '),
            c => out.push(c),
        }
        i += 1;
    }
    String::from_utf8_lossy(&out).into_owned()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn percent_decoding() {
        assert_eq!(percent_decode("a%20b+c"), "a b c");
        assert_eq!(percent_decode("100%"), "100%");
        assert_eq!(percent_decode("%4"), "%4");
        assert_eq!(percent_decode("%e2%82%ac"), "€");
    }

    #[test]
    fn constant_time_compare() {
        assert!(same(b"abc", b"abc"));
        assert!(!same(b"abc", b"abd"));
        assert!(!same(b"abc", b"ab"));
    }
}
