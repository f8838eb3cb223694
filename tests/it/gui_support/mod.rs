//! Support for the `sweepmtf gui` tests: the server started as a child process
//! (`--no-open`, a free port, killed on drop) and a minimal HTTP/1.1 client
//! over a TCP socket, so that any Host, Origin or token can be sent.

use std::io::{BufRead, BufReader, Read, Write};
use std::net::TcpStream;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::Duration;

/// The repository root (for testdata/ and targets/).
pub fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// The built `sweepmtf` binary (`SWEEPMTF_BIN` names another one, e.g. a
/// release build for the timings).
pub fn bin() -> PathBuf {
    match std::env::var_os("SWEEPMTF_BIN") {
        Some(p) => root().join(p),
        None => assert_cmd::cargo::cargo_bin("sweepmtf"),
    }
}

/// A running `sweepmtf gui`, stopped when dropped.
pub struct GuiProc {
    child: Child,
    /// Its stdout, kept open while it runs.
    _stdout: BufReader<std::process::ChildStdout>,
    /// The printed URL (with the token).
    pub url: String,
    /// The port.
    pub port: u16,
    /// The token.
    pub token: String,
}

impl GuiProc {
    /// Starts `sweepmtf gui ARGS --no-open` in `cwd` and reads the URL it prints.
    pub fn start(cwd: &Path, args: &[&str]) -> GuiProc {
        let mut child = Command::new(bin())
            .current_dir(cwd)
            .arg("gui")
            .args(args)
            .arg("--no-open")
            .stdout(Stdio::piped())
            .stderr(Stdio::inherit())
            .spawn()
            .expect("start sweepmtf gui");
        let mut line = String::new();
        let mut out = BufReader::new(child.stdout.take().unwrap());
        out.read_line(&mut line).unwrap();
        let url = line
            .trim()
            .strip_prefix("sweepmtf gui: ")
            .unwrap_or_else(|| panic!("unexpected first line: {line:?}"))
            .to_string();
        let rest = url.strip_prefix("http://127.0.0.1:").unwrap();
        let (port, query) = rest.split_once("/?token=").unwrap();
        GuiProc {
            port: port.parse().unwrap(),
            token: query.to_string(),
            url,
            child,
            _stdout: out,
        }
    }

    /// `127.0.0.1:PORT`.
    pub fn host(&self) -> String {
        format!("127.0.0.1:{}", self.port)
    }

    /// A request with the right Host and token header.
    pub fn call(&self, method: &str, path: &str, body: &[u8]) -> Reply {
        let tok = self.token.clone();
        http(
            self.port,
            method,
            path,
            &[("Host", &self.host()), ("X-Sweepmtf-Token", &tok)],
            body,
        )
    }

    /// POST JSON, returning the reply.
    pub fn post(&self, path: &str, v: &serde_json::Value) -> Reply {
        self.call("POST", path, v.to_string().as_bytes())
    }
}

impl Drop for GuiProc {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

/// An HTTP reply.
pub struct Reply {
    /// Status code.
    pub status: u16,
    /// Header lines (name, value).
    pub headers: Vec<(String, String)>,
    /// Body bytes.
    pub body: Vec<u8>,
}

impl Reply {
    /// The body as JSON (panics with the body when it is not).
    pub fn json(&self) -> serde_json::Value {
        serde_json::from_slice(&self.body)
            .unwrap_or_else(|e| panic!("not JSON ({e}): {}", String::from_utf8_lossy(&self.body)))
    }
    /// A header's value.
    pub fn header(&self, name: &str) -> Option<&str> {
        self.headers
            .iter()
            .find(|(k, _)| k.eq_ignore_ascii_case(name))
            .map(|(_, v)| v.as_str())
    }
}

/// One HTTP/1.1 request on a fresh connection (`Connection: close`); the
/// headers are sent exactly as given (no Host is added).
pub fn http(port: u16, method: &str, path: &str, headers: &[(&str, &str)], body: &[u8]) -> Reply {
    let mut s = TcpStream::connect(("127.0.0.1", port)).expect("connect");
    s.set_read_timeout(Some(Duration::from_secs(120))).unwrap();
    let mut req = format!("{method} {path} HTTP/1.1\r\n");
    for (k, v) in headers {
        req.push_str(&format!("{k}: {v}\r\n"));
    }
    if method != "GET" {
        req.push_str(&format!("Content-Length: {}\r\n", body.len()));
    }
    req.push_str("Connection: close\r\n\r\n");
    s.write_all(req.as_bytes()).unwrap();
    if method != "GET" {
        // The server may answer (413) and close before reading a body.
        let _ = s.write_all(body);
    }
    // Read until the body is complete (servers may keep the connection open).
    let mut raw = Vec::new();
    let mut buf = [0u8; 65536];
    loop {
        match s.read(&mut buf) {
            Ok(0) | Err(_) => break,
            Ok(n) => raw.extend_from_slice(&buf[..n]),
        }
        if let Some(end) = raw.windows(4).position(|w| w == b"\r\n\r\n") {
            let head = String::from_utf8_lossy(&raw[..end]).to_ascii_lowercase();
            let len = head
                .lines()
                .find_map(|l| l.strip_prefix("content-length:"))
                .and_then(|v| v.trim().parse::<usize>().ok());
            if len.is_some_and(|n| raw.len() >= end + 4 + n) {
                break;
            }
            if head.contains("chunked") && raw.ends_with(b"0\r\n\r\n") {
                break;
            }
        }
    }
    parse_reply(&raw)
}

fn parse_reply(raw: &[u8]) -> Reply {
    let end = raw
        .windows(4)
        .position(|w| w == b"\r\n\r\n")
        .unwrap_or_else(|| panic!("no header end in {:?}", String::from_utf8_lossy(raw)));
    let head = String::from_utf8_lossy(&raw[..end]).to_string();
    let mut lines = head.split("\r\n");
    let status: u16 = lines
        .next()
        .and_then(|l| l.split_whitespace().nth(1))
        .and_then(|c| c.parse().ok())
        .expect("status line");
    let headers: Vec<(String, String)> = lines
        .filter_map(|l| l.split_once(':'))
        .map(|(k, v)| (k.trim().to_string(), v.trim().to_string()))
        .collect();
    let mut body = raw[end + 4..].to_vec();
    let chunked = headers
        .iter()
        .any(|(k, v)| k.eq_ignore_ascii_case("transfer-encoding") && v.contains("chunked"));
    if chunked {
        body = dechunk(&body);
    }
    Reply {
        status,
        headers,
        body,
    }
}

fn dechunk(b: &[u8]) -> Vec<u8> {
    let mut out = Vec::new();
    let mut i = 0;
    while i < b.len() {
        let Some(nl) = b[i..].windows(2).position(|w| w == b"\r\n") else {
            break;
        };
        let size_text = String::from_utf8_lossy(&b[i..i + nl]).to_string();
        let size =
            usize::from_str_radix(size_text.split(';').next().unwrap().trim(), 16).unwrap_or(0);
        i += nl + 2;
        if size == 0 {
            break;
        }
        out.extend_from_slice(&b[i..(i + size).min(b.len())]);
        i += size + 2;
    }
    out
}
