//! The child process that runs inputs, and the parent's handle on it.
//!
//! The child is this binary again (`xtask fuzz-runner TARGET`). It reads inputs from stdin as
//! frames (`u32` LE length, bytes) and answers each on its own copy of stdout (the real fd 1
//! goes to /dev/null, so nothing a target prints can corrupt the protocol) with a status byte,
//! a `u32` LE length and a text: the outcome, or a caught panic's message and place.
//!
//! What is caught, and how:
//! - a panic: `catch_unwind` in the child (the child goes on with the next input);
//! - a hang: each input runs under `ITIMER_PROF` (process CPU time, all threads), so a child
//!   still busy after the budget dies of `SIGPROF` however loaded the machine is; a child
//!   that blocks without using CPU is killed by the parent after a wall-clock backstop;
//! - an allocation past the bound: the counting allocator (`bound.rs`) ends the child with
//!   its own exit status;
//! - anything else that ends the child (abort, stack overflow, a signal).
//!
//! Invariant: inputs are run one at a time and a verdict belongs to the input last sent, so a
//! batch attributes every failure to its exact input; the driver still confirms each in a
//! fresh child, since an earlier input may have left state behind.

use std::io::{Read, Write};
use std::path::{Path, PathBuf};
use std::process::{Child, ChildStdin, Command, Stdio};
use std::sync::mpsc::{self, Receiver, RecvTimeoutError};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use super::bound;
use super::targets::{self, Scratch};

const STATUS_DONE: u8 = 0;
const STATUS_PANIC: u8 = 1;

/// Limits every input runs under.
#[derive(Clone, Debug)]
pub struct Limits {
    /// CPU time per input.
    pub cpu: Duration,
    /// Live heap bytes (the whole child's).
    pub memory: usize,
}

impl Limits {
    /// A child that uses no CPU for this long is stuck, not slow: it is killed.
    fn wall_backstop(&self) -> Duration {
        (self.cpu * 20).max(Duration::from_secs(20))
    }
}

/// What became of one input.
#[derive(Clone, Debug, PartialEq)]
pub enum Verdict {
    /// Returned (accepted or refused), with the target's outcome.
    Fine(String),
    /// Panicked: message and place, and a backtrace in traced runs.
    Panic(String),
    /// Used more than the CPU budget (or blocked past the wall-clock backstop).
    Hang(String),
    /// Tried to take the live heap past the bound; the child's report.
    Memory(String),
    /// The child died otherwise: how, and the end of its stderr.
    Crash(String),
}

impl Verdict {
    pub fn is_fine(&self) -> bool {
        matches!(self, Verdict::Fine(_))
    }

    pub fn kind(&self) -> &'static str {
        match self {
            Verdict::Fine(_) => "fine",
            Verdict::Panic(_) => "panic",
            Verdict::Hang(_) => "hang",
            Verdict::Memory(_) => "memory",
            Verdict::Crash(_) => "crash",
        }
    }

    pub fn text(&self) -> &str {
        match self {
            Verdict::Fine(t)
            | Verdict::Panic(t)
            | Verdict::Hang(t)
            | Verdict::Memory(t)
            | Verdict::Crash(t) => t,
        }
    }
}

enum Reply {
    Status(u8, String),
    Closed,
}

/// A running child for one target.
pub struct Runner {
    child: Child,
    stdin: Option<ChildStdin>,
    replies: Receiver<Reply>,
    stderr: Arc<Mutex<Vec<u8>>>,
    stderr_thread: Option<std::thread::JoinHandle<()>>,
    limits: Limits,
    /// The child has died; a new runner is needed.
    pub dead: bool,
}

/// The parent's side: spawning, sending an input, reading its verdict.
impl Runner {
    /// Starts a child for `target`; `trace` asks for backtraces of panics and of the
    /// allocation that passes the bound.
    pub fn spawn(
        target: &str,
        scratch: &Path,
        limits: &Limits,
        trace: bool,
    ) -> Result<Runner, String> {
        let exe = std::env::current_exe().map_err(|e| format!("no path to this binary: {e}"))?;
        let mut cmd = Command::new(exe);
        cmd.arg("fuzz-runner")
            .arg(target)
            .env("LATTICEBUILD_FUZZ_SCRATCH", scratch)
            .env(
                "LATTICEBUILD_FUZZ_CPU_MS",
                limits.cpu.as_millis().to_string(),
            )
            .env("LATTICEBUILD_FUZZ_MEMORY", limits.memory.to_string())
            .env("LATTICEBUILD_FUZZ_TRACE", if trace { "1" } else { "0" })
            .env("RUST_BACKTRACE", if trace { "1" } else { "0" })
            .stdin(Stdio::piped())
            .stdout(Stdio::piped())
            .stderr(Stdio::piped());
        let mut child = cmd
            .spawn()
            .map_err(|e| format!("cannot start the fuzz runner: {e}"))?;
        let stdin = child.stdin.take();
        let mut stdout = child.stdout.take().ok_or("no runner stdout")?;
        let mut err_pipe = child.stderr.take().ok_or("no runner stderr")?;
        let (tx, replies) = mpsc::channel();
        std::thread::spawn(move || {
            loop {
                let mut head = [0u8; 5];
                if stdout.read_exact(&mut head).is_err() {
                    let _ = tx.send(Reply::Closed);
                    return;
                }
                let len = u32::from_le_bytes([head[1], head[2], head[3], head[4]]) as usize;
                let mut text = vec![0u8; len];
                if stdout.read_exact(&mut text).is_err() {
                    let _ = tx.send(Reply::Closed);
                    return;
                }
                let text = String::from_utf8_lossy(&text).into_owned();
                if tx.send(Reply::Status(head[0], text)).is_err() {
                    return;
                }
            }
        });
        let stderr = Arc::new(Mutex::new(Vec::new()));
        let sink = stderr.clone();
        let stderr_thread = std::thread::spawn(move || {
            let mut buf = [0u8; 4096];
            while let Ok(n) = err_pipe.read(&mut buf) {
                if n == 0 {
                    break;
                }
                let mut s = sink.lock().unwrap_or_else(|e| e.into_inner());
                s.extend_from_slice(&buf[..n]);
                // Only the end matters (a crash report); keep it bounded.
                if s.len() > 256 * 1024 {
                    let cut = s.len() - 128 * 1024;
                    s.drain(..cut);
                }
            }
        });
        Ok(Runner {
            child,
            stdin,
            replies,
            stderr,
            stderr_thread: Some(stderr_thread),
            limits: limits.clone(),
            dead: false,
        })
    }

    /// Runs one input and returns its verdict. After any verdict but `Fine` and `Panic` the
    /// child is dead.
    pub fn run(&mut self, input: &[u8]) -> Verdict {
        assert!(!self.dead, "a dead runner was asked to run an input");
        self.stderr
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .clear();
        let sent = self.stdin.as_mut().is_some_and(|stdin| {
            let len = u32::try_from(input.len()).unwrap_or(u32::MAX);
            stdin.write_all(&len.to_le_bytes()).is_ok()
                && stdin.write_all(&input[..len as usize]).is_ok()
                && stdin.flush().is_ok()
        });
        let started = Instant::now();
        let reply = if sent {
            self.replies.recv_timeout(self.limits.wall_backstop())
        } else {
            Err(RecvTimeoutError::Disconnected)
        };
        match reply {
            Ok(Reply::Status(STATUS_DONE, text)) => Verdict::Fine(text),
            Ok(Reply::Status(_, text)) => Verdict::Panic(text),
            Err(RecvTimeoutError::Timeout) => {
                let _ = self.child.kill();
                self.finish();
                Verdict::Hang(format!(
                    "no answer after {:.1} s of wall-clock time (killed)",
                    started.elapsed().as_secs_f64()
                ))
            }
            Ok(Reply::Closed) | Err(RecvTimeoutError::Disconnected) => self.death(),
        }
    }

    /// Waits for the dead child and collects its stderr.
    fn finish(&mut self) -> (Option<std::process::ExitStatus>, String) {
        self.dead = true;
        self.stdin = None;
        let status = self.child.wait().ok();
        if let Some(t) = self.stderr_thread.take() {
            let _ = t.join();
        }
        let err = self.stderr.lock().unwrap_or_else(|e| e.into_inner());
        (status, String::from_utf8_lossy(&err).into_owned())
    }

    fn death(&mut self) -> Verdict {
        use std::os::unix::process::ExitStatusExt;
        let (status, stderr) = self.finish();
        let stderr = stderr.trim().to_string();
        match status {
            Some(s) if s.signal() == Some(libc::SIGPROF) => Verdict::Hang(format!(
                "over the CPU budget of {:.1} s (SIGPROF)\n{stderr}",
                self.limits.cpu.as_secs_f64()
            )),
            Some(s) if s.code() == Some(bound::OVER_BOUND_EXIT) => Verdict::Memory(stderr),
            Some(s) => Verdict::Crash(format!("{s}\n{stderr}")),
            None => Verdict::Crash(format!("the runner could not be waited for\n{stderr}")),
        }
    }
}

impl Drop for Runner {
    fn drop(&mut self) {
        if !self.dead {
            // Closing stdin ends a healthy child; kill one that is mid-input.
            self.stdin = None;
            let _ = self.child.kill();
            let _ = self.child.wait();
        }
    }
}

/// Arms (or, with zero, disarms) the CPU-time timer of this process: `SIGPROF` when spent.
fn cpu_timer(budget: Duration) {
    let value = libc::itimerval {
        it_interval: libc::timeval {
            tv_sec: 0,
            tv_usec: 0,
        },
        it_value: libc::timeval {
            tv_sec: budget.as_secs() as libc::time_t,
            tv_usec: budget.subsec_micros() as libc::suseconds_t,
        },
    };
    // SAFETY: a valid itimerval; the old value is not asked for.
    unsafe { libc::setitimer(libc::ITIMER_PROF, &value, std::ptr::null_mut()) };
}

fn env_number(name: &str) -> Option<u64> {
    std::env::var(name).ok()?.parse().ok()
}

/// The child's side: `xtask fuzz-runner TARGET`. Returns when stdin ends.
pub fn serve(target: &str) -> Result<(), String> {
    let target = targets::find(target).ok_or_else(|| format!("no fuzz target `{target}`"))?;
    let scratch = Scratch {
        dir: std::env::var_os("LATTICEBUILD_FUZZ_SCRATCH")
            .map(PathBuf::from)
            .ok_or("the fuzz runner needs LATTICEBUILD_FUZZ_SCRATCH")?,
    };
    let cpu = Duration::from_millis(env_number("LATTICEBUILD_FUZZ_CPU_MS").unwrap_or(1000));
    let trace = std::env::var("LATTICEBUILD_FUZZ_TRACE").as_deref() == Ok("1");

    // The protocol gets its own descriptor; fd 1 goes to /dev/null.
    // SAFETY: plain descriptor calls on descriptors this process owns.
    let mut answers = unsafe {
        use std::os::fd::FromRawFd;
        let fd = libc::dup(1);
        if fd < 0 {
            return Err("cannot duplicate stdout".into());
        }
        let null = libc::open(c"/dev/null".as_ptr(), libc::O_WRONLY);
        if null >= 0 {
            libc::dup2(null, 1);
            libc::close(null);
        }
        std::fs::File::from_raw_fd(fd)
    };

    let caught: Arc<Mutex<Option<String>>> = Arc::new(Mutex::new(None));
    let hook_slot = caught.clone();
    std::panic::set_hook(Box::new(move |info| {
        let message = if let Some(s) = info.payload().downcast_ref::<&str>() {
            s.to_string()
        } else if let Some(s) = info.payload().downcast_ref::<String>() {
            s.clone()
        } else {
            "(a panic without a message)".to_string()
        };
        let place = info
            .location()
            .map(|l| format!("{}:{}:{}", l.file(), l.line(), l.column()))
            .unwrap_or_default();
        let mut text = format!("panicked at {place}: {message}");
        if trace {
            text.push_str(&format!("\n{}", std::backtrace::Backtrace::force_capture()));
        }
        *hook_slot.lock().unwrap_or_else(|e| e.into_inner()) = Some(text);
    }));

    if let Some(bytes) = env_number("LATTICEBUILD_FUZZ_MEMORY") {
        bound::trace_on_bound(trace);
        bound::set_bound(bytes as usize);
    }

    let mut stdin = std::io::stdin().lock();
    loop {
        let mut len = [0u8; 4];
        if stdin.read_exact(&mut len).is_err() {
            return Ok(());
        }
        let mut input = vec![0u8; u32::from_le_bytes(len) as usize];
        if stdin.read_exact(&mut input).is_err() {
            return Ok(());
        }
        cpu_timer(cpu);
        let result = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
            (target.run)(&input, &scratch)
        }));
        cpu_timer(Duration::ZERO);
        let (status, text) = match result {
            Ok(outcome) => (STATUS_DONE, outcome),
            Err(_) => (
                STATUS_PANIC,
                caught
                    .lock()
                    .unwrap_or_else(|e| e.into_inner())
                    .take()
                    .unwrap_or_else(|| "panicked".into()),
            ),
        };
        let mut reply = vec![status];
        reply.extend_from_slice(&(text.len() as u32).to_le_bytes());
        reply.extend_from_slice(text.as_bytes());
        if answers
            .write_all(&reply)
            .and_then(|()| answers.flush())
            .is_err()
        {
            return Ok(());
        }
    }
}
