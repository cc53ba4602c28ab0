//! One websocket connection to a model server (`ws://HOST:PORT[/PATH]`, plain TCP): connecting
//! with retries and exponential backoff, binary frames out and frames in by a deadline (one per
//! exchange: what the server sends meanwhile never extends it), and every way that goes wrong as
//! a [`WireError`]. A failed connection is dropped, so the next episode
//! connects afresh.
//!
//! It does not know any message format (see `openpi` and `vla_eval`).

use policy::WireError;
use std::io::{ErrorKind, Read, Write};
use std::net::{SocketAddr, TcpStream, ToSocketAddrs};
use std::time::{Duration, Instant};
use tungstenite::{Message, WebSocket};

/// A received frame.
pub enum Frame {
    Binary(Vec<u8>),
    Text(String),
}

pub struct Link {
    pub url: String,
    addr: String,
    /// Reply timeout.
    pub timeout: Duration,
    /// Connection attempts before giving up (at least 1).
    pub attempts: u32,
    /// The first retry's wait; doubled for each further retry.
    pub backoff: Duration,
    socket: Option<WebSocket<Timed>>,
}

/// Why one connection attempt failed.
#[derive(Debug, thiserror::Error)]
enum OpenError {
    #[error("cannot resolve {addr}: {source}")]
    Resolve {
        addr: String,
        source: std::io::Error,
    },
    #[error("{addr} resolves to no address")]
    NoAddress { addr: String },
    /// The last address's TCP connection failed.
    #[error(transparent)]
    Tcp(std::io::Error),
    #[error("websocket handshake failed: {0}")]
    Handshake(Box<tungstenite::HandshakeError<tungstenite::ClientHandshake<Timed>>>),
}

/// The longest wait between connection attempts.
const MAX_BACKOFF: Duration = Duration::from_secs(30);

/// A TCP stream whose reads and writes end at a deadline: every read or write waits at most the
/// time left, so a server that pings, trickles a frame byte by byte, or reads a request slowly
/// cannot stretch an exchange past its timeout.
#[derive(Debug)]
struct Timed {
    stream: TcpStream,
    deadline: Option<Instant>,
}

impl Read for Timed {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        if let Some(d) = self.deadline {
            let left = d.saturating_duration_since(Instant::now());
            if left.is_zero() {
                return Err(ErrorKind::TimedOut.into());
            }
            self.stream.set_read_timeout(Some(left))?;
        }
        self.stream.read(buf)
    }
}

impl Write for Timed {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        if let Some(d) = self.deadline {
            let left = d.saturating_duration_since(Instant::now());
            if left.is_zero() {
                return Err(ErrorKind::TimedOut.into());
            }
            self.stream.set_write_timeout(Some(left))?;
        }
        self.stream.write(buf)
    }
    fn flush(&mut self) -> std::io::Result<()> {
        self.stream.flush()
    }
}

impl Link {
    pub fn new(url: &str, timeout: Duration) -> Result<Link, WireError> {
        let bad = |why: &str| WireError::Address {
            url: url.to_string(),
            why: why.to_string(),
        };
        let rest = match url.split_once("://") {
            Some(("ws", rest)) => rest,
            Some(("wss", _)) => return Err(bad("wss:// (TLS) is not supported; use ws://")),
            _ => return Err(bad("expected ws://HOST:PORT")),
        };
        let host_port = rest.split('/').next().unwrap_or_default();
        if host_port.is_empty() {
            return Err(bad("no host"));
        }
        let addr = if host_port
            .rsplit_once(':')
            .is_some_and(|(_, p)| p.parse::<u16>().is_ok())
        {
            host_port.to_string()
        } else {
            format!("{host_port}:80")
        };
        Ok(Link {
            url: url.to_string(),
            addr,
            timeout,
            attempts: 4,
            backoff: Duration::from_millis(250),
            socket: None,
        })
    }

    pub fn is_open(&self) -> bool {
        self.socket.is_some()
    }

    /// Connects if not connected, retrying with exponential backoff. Returns whether a new
    /// connection was made.
    pub fn ensure_open(&mut self) -> Result<bool, WireError> {
        if self.socket.is_some() {
            return Ok(false);
        }
        let start = Instant::now();
        let mut wait = self.backoff;
        let mut last = String::new();
        for attempt in 1..=self.attempts.max(1) {
            match self.open_once() {
                Ok(ws) => {
                    self.socket = Some(ws);
                    return Ok(true);
                }
                Err(e) => last = e.to_string(),
            }
            if attempt < self.attempts {
                std::thread::sleep(wait);
                wait = (wait * 2).min(MAX_BACKOFF);
            }
        }
        Err(WireError::Connect {
            url: self.url.clone(),
            attempts: self.attempts.max(1),
            waited_s: start.elapsed().as_secs_f64(),
            last,
        })
    }

    fn open_once(&self) -> Result<WebSocket<Timed>, OpenError> {
        let addrs: Vec<SocketAddr> = self
            .addr
            .to_socket_addrs()
            .map_err(|source| OpenError::Resolve {
                addr: self.addr.clone(),
                source,
            })?
            .collect();
        let mut last = OpenError::NoAddress {
            addr: self.addr.clone(),
        };
        for a in addrs {
            match TcpStream::connect_timeout(&a, self.timeout) {
                Ok(stream) => {
                    stream.set_nodelay(true).ok();
                    let timed = Timed {
                        stream,
                        deadline: Some(Instant::now() + self.timeout),
                    };
                    return match tungstenite::client(self.url.as_str(), timed) {
                        Ok((mut ws, _)) => {
                            ws.get_mut().deadline = None;
                            Ok(ws)
                        }
                        Err(e) => Err(OpenError::Handshake(Box::new(e))),
                    };
                }
                Err(e) => last = OpenError::Tcp(e),
            }
        }
        Err(last)
    }

    /// Drops the connection (after a failure: its state is unknown).
    pub fn drop_connection(&mut self) {
        if let Some(mut ws) = self.socket.take() {
            ws.close(None).ok();
            ws.flush().ok();
        }
    }

    fn fail<T>(&mut self, e: WireError) -> Result<T, WireError> {
        self.drop_connection();
        Err(e)
    }

    /// The deadline of an exchange starting now: the request out and its whole reply in, within
    /// the reply timeout.
    pub fn deadline(&self) -> Instant {
        Instant::now() + self.timeout
    }

    /// Sends one binary frame within its own timeout.
    pub fn send(&mut self, bytes: Vec<u8>) -> Result<(), WireError> {
        self.send_by(bytes, self.deadline())
    }

    /// Sends one binary frame, giving up at `deadline`.
    pub fn send_by(&mut self, bytes: Vec<u8>, deadline: Instant) -> Result<(), WireError> {
        let timeout_s = self.timeout.as_secs_f64();
        let Some(ws) = self.socket.as_mut() else {
            return Err(WireError::Closed(" before the request".into()));
        };
        ws.get_mut().deadline = Some(deadline);
        let sent = ws.send(Message::binary(bytes));
        ws.get_mut().deadline = None;
        match sent {
            Ok(()) => Ok(()),
            Err(e) => {
                let e = classify(e, timeout_s);
                self.fail(e)
            }
        }
    }

    /// The next data frame if one comes within `wait`; `None` (the connection kept) if none does.
    pub fn try_recv(&mut self, wait: Duration) -> Result<Option<Frame>, WireError> {
        match self.recv_inner(Instant::now() + wait, wait.as_secs_f64()) {
            Ok(f) => Ok(Some(f)),
            Err(WireError::Timeout(_)) => Ok(None),
            Err(e) => self.fail(e),
        }
    }

    /// The next data frame, by `deadline` (an exchange's, from [`Link::deadline`]: a reply read
    /// as several frames shares one). Pings are answered; a close frame is
    /// [`WireError::Closed`]; a missed deadline is [`WireError::Timeout`] with the timeout.
    pub fn recv_by(&mut self, deadline: Instant) -> Result<Frame, WireError> {
        match self.recv_inner(deadline, self.timeout.as_secs_f64()) {
            Ok(f) => Ok(f),
            Err(e) => self.fail(e),
        }
    }

    fn recv_inner(&mut self, deadline: Instant, timeout_s: f64) -> Result<Frame, WireError> {
        let Some(ws) = self.socket.as_mut() else {
            return Err(WireError::Closed(" before the reply".into()));
        };
        // One deadline for the whole reply: pings and partial frames do not extend it.
        ws.get_mut().deadline = Some(deadline);
        let result = loop {
            match ws.read() {
                Ok(Message::Binary(b)) => break Ok(Frame::Binary(b.to_vec())),
                Ok(Message::Text(t)) => break Ok(Frame::Text(t.to_string())),
                Ok(Message::Close(c)) => {
                    break Err(WireError::Closed(match c {
                        Some(c) if !c.reason.is_empty() => {
                            format!(" (code {}: {})", u16::from(c.code), c.reason)
                        }
                        Some(c) => format!(" (code {})", u16::from(c.code)),
                        None => String::new(),
                    }));
                }
                Ok(_) => continue,
                Err(e) => break Err(classify(e, timeout_s)),
            }
        };
        ws.get_mut().deadline = None;
        result
    }
}

fn classify(e: tungstenite::Error, timeout_s: f64) -> WireError {
    use tungstenite::Error as E;
    match e {
        E::Io(io) if matches!(io.kind(), ErrorKind::WouldBlock | ErrorKind::TimedOut) => {
            WireError::Timeout(timeout_s)
        }
        E::ConnectionClosed | E::AlreadyClosed => WireError::Closed(String::new()),
        E::Io(io) => WireError::Closed(format!(": {io}")),
        E::Protocol(p) => WireError::Closed(format!(" ({p})")),
        other => WireError::Malformed(other.to_string()),
    }
}
