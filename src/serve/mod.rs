//! `latticebuild watch --serve`: a local web page showing the outputs of the watched build in
//! a WebGL viewer, updated by itself after every rebuild.
//!
//! Parts: [`http`] (a small blocking HTTP/1.1 server on `std::net`, fixed routes only),
//! [`state`] (what the page is told after each build: reports, stage graph, last error, and
//! each output's display mesh), [`mesh`] (reading, welding, decimating and encoding a mesh),
//! [`assets`] (the page and the vendored three.js, embedded at build time).
//!
//! Invariants:
//! - The server reads no file: every answer comes from memory — the embedded assets or the
//!   [`Published`] state the watch loop hands over after a build. A URL is only ever compared
//!   with the fixed routes and with output names, so no path from a request can reach the
//!   filesystem (the meshes are read by the watch loop, from the paths in the build's reports).
//! - Only `GET` and `HEAD`; a `Host` header that does not name the bound address is refused
//!   (DNS rebinding); nothing a request does changes any state.
//! - State moves forward by generation: each publish bumps it and wakes every event stream.

pub mod assets;
pub mod http;
pub mod mesh;
pub mod state;

use std::net::{SocketAddr, TcpListener};
use std::sync::{Arc, Condvar, Mutex};

pub use state::Published;

/// The state the watch loop publishes and the connections read.
#[derive(Default)]
pub struct Shared {
    current: Mutex<Arc<Published>>,
    changed: Condvar,
}

impl Shared {
    /// The latest state.
    pub fn get(&self) -> Arc<Published> {
        match self.current.lock() {
            Ok(guard) => Arc::clone(&guard),
            Err(poisoned) => Arc::clone(&poisoned.into_inner()),
        }
    }

    /// Replaces the state (its generation one past the last) and wakes the event streams.
    pub fn publish(&self, mut next: Published) {
        let mut guard = match self.current.lock() {
            Ok(guard) => guard,
            Err(poisoned) => poisoned.into_inner(),
        };
        next.generation = guard.generation + 1;
        *guard = Arc::new(next);
        self.changed.notify_all();
    }

    /// Waits up to `timeout` for a generation newer than `seen`; the latest state either way.
    pub fn wait_newer(&self, seen: u64, timeout: std::time::Duration) -> Arc<Published> {
        let guard = match self.current.lock() {
            Ok(guard) => guard,
            Err(poisoned) => poisoned.into_inner(),
        };
        let guard = match self
            .changed
            .wait_timeout_while(guard, timeout, |s| s.generation <= seen)
        {
            Ok((guard, _)) => guard,
            Err(poisoned) => poisoned.into_inner().0,
        };
        Arc::clone(&guard)
    }
}

/// A running server.
pub struct Server {
    pub shared: Arc<Shared>,
    pub address: SocketAddr,
}

/// Parses `--serve`'s address: `IP:PORT`, `[IPv6]:PORT`, or `localhost:PORT`.
pub fn parse_address(text: &str) -> Result<SocketAddr, String> {
    if let Some(port) = text.strip_prefix("localhost:") {
        let port: u16 = port
            .parse()
            .map_err(|_| format!("`{text}`: the port is not a number from 0 to 65535"))?;
        return Ok(SocketAddr::from(([127, 0, 0, 1], port)));
    }
    text.parse().map_err(|_| {
        format!("`{text}` is not an address to serve on (like 127.0.0.1:8700 or [::1]:8700)")
    })
}

impl Server {
    /// Binds `address` and serves from a thread of its own (one more per connection).
    pub fn start(address: SocketAddr) -> std::io::Result<Server> {
        let listener = TcpListener::bind(address)?;
        let address = listener.local_addr()?;
        let shared = Arc::new(Shared::default());
        let serving = Arc::clone(&shared);
        std::thread::Builder::new()
            .name("serve".into())
            .spawn(move || http::accept(listener, address, serving))?;
        Ok(Server { shared, address })
    }
}
