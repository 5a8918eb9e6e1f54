//! The HTTP side of `watch --serve`: one thread per connection, one request per connection
//! (`Connection: close`), fixed routes.
//!
//! Invariants:
//! - A request is answered only after its `Host` header names the bound address (for a
//!   loopback address also `localhost:PORT`; for an unspecified one any IP literal with the
//!   port): a page from another origin that rebinds its DNS name to this machine is refused
//!   (403), so it cannot read the state.
//! - Only `GET` and `HEAD` (405 otherwise). The request target is compared with the fixed
//!   routes and, under `/api/mesh/`, with the output names in memory; it is never decoded
//!   into a path and nothing is read from disk (404 for everything else).
//! - A request head is at most 16 KiB and must arrive within 5 s; at most 64 connections are
//!   served at once (each event stream holds one), more are closed unanswered.

use std::io::{self, Read, Write};
use std::net::{SocketAddr, TcpListener, TcpStream};
use std::sync::Arc;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::Duration;

use super::{Shared, assets};

const MAX_HEAD: usize = 16 * 1024;
const MAX_CONNECTIONS: usize = 64;
/// An idle event stream sends a comment this often, so a closed page ends its thread.
const KEEP_ALIVE: Duration = Duration::from_secs(15);

/// Serves `listener` until the process ends.
pub fn accept(listener: TcpListener, bound: SocketAddr, shared: Arc<Shared>) {
    let live = Arc::new(AtomicUsize::new(0));
    for stream in listener.incoming() {
        let Ok(stream) = stream else { continue };
        if live.fetch_add(1, Ordering::SeqCst) >= MAX_CONNECTIONS {
            live.fetch_sub(1, Ordering::SeqCst);
            continue;
        }
        let shared = Arc::clone(&shared);
        let count = Arc::clone(&live);
        let spawned = std::thread::Builder::new()
            .name("serve-connection".into())
            .spawn(move || {
                let _ = handle(stream, bound, &shared);
                count.fetch_sub(1, Ordering::SeqCst);
            });
        if spawned.is_err() {
            live.fetch_sub(1, Ordering::SeqCst);
        }
    }
}

/// A parsed request head.
#[derive(Debug, PartialEq)]
pub struct Request {
    pub method: String,
    pub target: String,
    pub host: Option<String>,
}

/// Parses a request head (without the final blank line). `Err` is the status to answer.
pub fn parse_head(head: &str) -> Result<Request, u16> {
    let mut lines = head.split("\r\n");
    let mut words = lines.next().unwrap_or("").split(' ');
    let (Some(method), Some(target), Some(version), None) =
        (words.next(), words.next(), words.next(), words.next())
    else {
        return Err(400);
    };
    if !version.starts_with("HTTP/1.") || method.is_empty() || target.is_empty() {
        return Err(400);
    }
    let mut host = None;
    for line in lines {
        let Some((name, value)) = line.split_once(':') else {
            return Err(400);
        };
        if name.eq_ignore_ascii_case("host") {
            if host.is_some() {
                return Err(400);
            }
            host = Some(value.trim().to_string());
        }
    }
    Ok(Request {
        method: method.to_string(),
        target: target.to_string(),
        host,
    })
}

/// Whether `host` (a `Host` header) names the address the server is bound to.
pub fn host_allowed(host: &str, bound: SocketAddr) -> bool {
    let host = host.to_ascii_lowercase();
    let port = bound.port();
    // Browsers leave out the default port.
    let has_port = if host.starts_with('[') {
        !host.ends_with(']')
    } else {
        host.contains(':')
    };
    let host = if has_port { host } else { format!("{host}:80") };
    if host == bound.to_string() {
        return true;
    }
    if (bound.ip().is_loopback() || bound.ip().is_unspecified())
        && host == format!("localhost:{port}")
    {
        return true;
    }
    bound.ip().is_unspecified() && host.parse::<SocketAddr>().is_ok_and(|a| a.port() == port)
}

fn reason(status: u16) -> &'static str {
    match status {
        200 => "OK",
        400 => "Bad Request",
        403 => "Forbidden",
        404 => "Not Found",
        405 => "Method Not Allowed",
        _ => "Error",
    }
}

fn respond(
    stream: &mut TcpStream,
    status: u16,
    content_type: &str,
    body: &[u8],
    head_only: bool,
) -> io::Result<()> {
    let mut head = format!(
        "HTTP/1.1 {status} {}\r\nContent-Type: {content_type}\r\nContent-Length: {}\r\n\
         Cache-Control: no-store\r\nX-Content-Type-Options: nosniff\r\n\
         Content-Security-Policy: default-src 'self'; style-src 'self' 'unsafe-inline'; \
         frame-ancestors 'none'\r\nConnection: close\r\n",
        reason(status),
        body.len()
    );
    if status == 405 {
        head.push_str("Allow: GET, HEAD\r\n");
    }
    head.push_str("\r\n");
    stream.write_all(head.as_bytes())?;
    if !head_only {
        stream.write_all(body)?;
    }
    stream.flush()
}

fn error(stream: &mut TcpStream, status: u16, text: &str) -> io::Result<()> {
    respond(
        stream,
        status,
        "text/plain; charset=utf-8",
        format!("{status} {}: {text}\n", reason(status)).as_bytes(),
        false,
    )
}

/// Reads up to the blank line ending the head.
fn read_head(stream: &mut TcpStream) -> Result<String, u16> {
    let mut head = Vec::new();
    let mut buffer = [0u8; 2048];
    loop {
        let n = stream.read(&mut buffer).map_err(|_| 400u16)?;
        if n == 0 {
            return Err(400);
        }
        head.extend_from_slice(&buffer[..n]);
        if let Some(end) = head.windows(4).position(|w| w == b"\r\n\r\n") {
            head.truncate(end);
            return String::from_utf8(head).map_err(|_| 400);
        }
        if head.len() > MAX_HEAD {
            return Err(400);
        }
    }
}

fn handle(mut stream: TcpStream, bound: SocketAddr, shared: &Shared) -> io::Result<()> {
    stream.set_read_timeout(Some(Duration::from_secs(5)))?;
    stream.set_write_timeout(Some(Duration::from_secs(30)))?;
    let request = match read_head(&mut stream).and_then(|h| parse_head(&h)) {
        Ok(r) => r,
        Err(status) => return error(&mut stream, status, "malformed request"),
    };
    if !request
        .host
        .as_deref()
        .is_some_and(|h| host_allowed(h, bound))
    {
        return error(
            &mut stream,
            403,
            &format!("this server answers only to Host: {bound}"),
        );
    }
    let head_only = match request.method.as_str() {
        "GET" => false,
        "HEAD" => true,
        _ => return error(&mut stream, 405, "only GET and HEAD"),
    };
    // The query (the page's cache-busting `?v=`) plays no part in routing.
    let path = request
        .target
        .split_once('?')
        .map_or(request.target.as_str(), |(p, _)| p);
    if let Some(asset) = assets::find(path) {
        return respond(&mut stream, 200, asset.content_type, asset.bytes, head_only);
    }
    match path {
        "/api/state" => {
            let state = shared.get();
            respond(
                &mut stream,
                200,
                "application/json",
                &state.json(),
                head_only,
            )
        }
        "/events" if !head_only => events(stream, shared),
        _ => {
            if let Some(name) = path.strip_prefix("/api/mesh/") {
                let state = shared.get();
                if let Some(bytes) = state.meshes.get(name) {
                    return respond(
                        &mut stream,
                        200,
                        "application/octet-stream",
                        bytes,
                        head_only,
                    );
                }
            }
            error(&mut stream, 404, "no such page")
        }
    }
}

/// A server-sent event stream: `event: state` with the generation after every publish.
fn events(mut stream: TcpStream, shared: &Shared) -> io::Result<()> {
    stream.write_all(
        b"HTTP/1.1 200 OK\r\nContent-Type: text/event-stream\r\nCache-Control: no-store\r\n\
          X-Content-Type-Options: nosniff\r\nConnection: close\r\n\r\nretry: 1000\n\n",
    )?;
    let mut seen = 0;
    loop {
        let state = shared.wait_newer(seen, KEEP_ALIVE);
        if state.generation > seen {
            seen = state.generation;
            write!(stream, "event: state\ndata: {seen}\n\n")?;
        } else {
            stream.write_all(b": keep-alive\n\n")?;
        }
        stream.flush()?;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn heads_parse_and_malformed_ones_are_refused() {
        let r = parse_head("GET /api/state?x=1 HTTP/1.1\r\nhOsT: 127.0.0.1:8700\r\nAccept: */*")
            .expect("parses");
        assert_eq!(r.method, "GET");
        assert_eq!(r.target, "/api/state?x=1");
        assert_eq!(r.host.as_deref(), Some("127.0.0.1:8700"));
        assert_eq!(parse_head("GET /"), Err(400));
        assert_eq!(parse_head("GET / HTTP/1.1 extra"), Err(400));
        assert_eq!(parse_head("GET / SMTP/1.0"), Err(400));
        assert_eq!(parse_head("GET / HTTP/1.1\r\nno colon here"), Err(400));
        assert_eq!(
            parse_head("GET / HTTP/1.1\r\nHost: a:1\r\nHost: b:2"),
            Err(400)
        );
    }

    #[test]
    fn only_the_bound_address_is_an_allowed_host() {
        let loopback: SocketAddr = "127.0.0.1:8700".parse().expect("addr");
        assert!(host_allowed("127.0.0.1:8700", loopback));
        assert!(host_allowed("LOCALHOST:8700", loopback));
        assert!(!host_allowed("localhost:8701", loopback));
        assert!(!host_allowed("evil.example:8700", loopback));
        assert!(!host_allowed("127.0.0.1", loopback));
        assert!(!host_allowed("127.0.0.1:8700.evil.example", loopback));
        let v6: SocketAddr = "[::1]:9000".parse().expect("addr");
        assert!(host_allowed("[::1]:9000", v6));
        assert!(!host_allowed("::1:9000", v6));
        let any: SocketAddr = "0.0.0.0:8700".parse().expect("addr");
        assert!(host_allowed("192.168.1.20:8700", any));
        assert!(!host_allowed("192.168.1.20:8701", any));
        assert!(!host_allowed("lattice.example:8700", any));
        let web: SocketAddr = "10.0.0.5:80".parse().expect("addr");
        assert!(host_allowed("10.0.0.5", web));
        assert!(host_allowed("10.0.0.5:80", web));
        assert!(!host_allowed("10.0.0.6", web));
    }
}
