//! The Blender worker process: `worker.py` (embedded in the binary) run by the Python of the
//! environment `make setup` makes (`.deps/blender-env`, the `bpy` wheel), spoken to over its
//! standard input and output with length-framed messages (a JSON header and a binary blob each).
//! Blender's own output goes to the worker's standard error, whose last lines are kept to explain
//! a worker that dies.
//!
//! It knows nothing of scenes: [`super::stage`] writes the requests, [`super::Cameras`] reads
//! the answers.

use std::collections::VecDeque;
use std::io::{BufRead, BufReader, BufWriter, Read, Write};
use std::path::PathBuf;
use std::process::{Child, ChildStdin, ChildStdout, Command, Stdio};
use std::sync::{Arc, Mutex};

const SCRIPT: &str = include_str!("worker.py");

/// Lines of the worker's standard error kept for an error message.
const TAIL_LINES: usize = 30;

/// The longest header and blob an answer may announce: anything longer is not the worker
/// speaking (a stray write on its standard output), refused before allocating.
const MAX_HEADER: usize = 1 << 20;
const MAX_BLOB: u64 = 1 << 32;

/// Why Blender could not draw.
#[derive(Debug, thiserror::Error)]
pub enum BlenderError {
    #[error(
        "Blender's Python is not at {}: run `make setup` (it installs the `bpy` wheel there), or point AUTOBIO_BLENDER_PYTHON at a Python 3.11 with `bpy` 5.0",
        path.display()
    )]
    NotInstalled { path: PathBuf },
    #[error("cannot start the Blender worker ({}): {why}", path.display())]
    Start { path: PathBuf, why: std::io::Error },
    #[error("the Blender worker stopped ({why}); its last words:\n{tail}")]
    Died { why: String, tail: String },
    #[error("Blender refused the {op} request: {error}")]
    Refused { op: String, error: String },
    #[error("the Blender worker answered what is not a frame: {0}")]
    Answer(String),
}

impl From<BlenderError> for crate::render::RenderError {
    fn from(e: BlenderError) -> Self {
        crate::render::RenderError::Blender(Box::new(e))
    }
}

/// The Python that runs the worker: `$AUTOBIO_BLENDER_PYTHON`, else the environment `make setup`
/// made under the dependencies folder.
pub fn python() -> PathBuf {
    if let Ok(p) = std::env::var("AUTOBIO_BLENDER_PYTHON") {
        return PathBuf::from(p);
    }
    crate::deps::deps_dir().join("blender-env/bin/python")
}

/// Whether Blender's Python is installed (the worker may still fail to start).
pub fn installed() -> bool {
    python().is_file()
}

pub struct Worker {
    child: Child,
    to: BufWriter<ChildStdin>,
    from: BufReader<ChildStdout>,
    tail: Arc<Mutex<VecDeque<String>>>,
    /// Blender's version, as the worker reported it.
    pub blender: String,
}

impl Worker {
    pub fn start() -> Result<Worker, BlenderError> {
        let path = python();
        if !path.is_file() {
            return Err(BlenderError::NotInstalled { path });
        }
        let mut child = Command::new(&path)
            .arg("-c")
            .arg(SCRIPT)
            .stdin(Stdio::piped())
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .map_err(|why| BlenderError::Start {
                path: path.clone(),
                why,
            })?;
        let tail = Arc::new(Mutex::new(VecDeque::new()));
        let stderr = child.stderr.take().expect("piped above");
        let keep = tail.clone();
        std::thread::spawn(move || {
            for line in BufReader::new(stderr).lines().map_while(Result::ok) {
                let mut t = keep.lock().unwrap_or_else(|p| p.into_inner());
                if t.len() == TAIL_LINES {
                    t.pop_front();
                }
                t.push_back(line);
            }
        });
        let mut w = Worker {
            to: BufWriter::new(child.stdin.take().expect("piped above")),
            from: BufReader::new(child.stdout.take().expect("piped above")),
            child,
            tail,
            blender: String::new(),
        };
        let (hello, _) = w.receive("start")?;
        w.blender = hello["blender"].as_str().unwrap_or("?").to_string();
        Ok(w)
    }

    /// Sends a request and waits for its answer (header, blob).
    pub fn request(
        &mut self,
        header: &serde_json::Value,
        blob: &[u8],
    ) -> Result<(serde_json::Value, Vec<u8>), BlenderError> {
        let op = header["op"].as_str().unwrap_or("?").to_string();
        let h = serde_json::to_vec(header).expect("a JSON value serialises");
        let sent = (|| {
            self.to.write_all(&(h.len() as u32).to_le_bytes())?;
            self.to.write_all(&h)?;
            self.to.write_all(&(blob.len() as u64).to_le_bytes())?;
            self.to.write_all(blob)?;
            self.to.flush()
        })();
        if let Err(e) = sent {
            return Err(self.died(format!("cannot send the {op} request: {e}")));
        }
        self.receive(&op)
    }

    fn receive(&mut self, op: &str) -> Result<(serde_json::Value, Vec<u8>), BlenderError> {
        let mut read = || -> std::io::Result<(Vec<u8>, Vec<u8>)> {
            let mut n = [0u8; 4];
            self.from.read_exact(&mut n)?;
            let too_long = |what: &str, n: u64| {
                std::io::Error::new(
                    std::io::ErrorKind::InvalidData,
                    format!("a {what} of {n} bytes announced: not the worker's answer"),
                )
            };
            let header_len = u32::from_le_bytes(n) as usize;
            if header_len > MAX_HEADER {
                return Err(too_long("header", header_len as u64));
            }
            let mut h = vec![0u8; header_len];
            self.from.read_exact(&mut h)?;
            let mut m = [0u8; 8];
            self.from.read_exact(&mut m)?;
            let blob_len = u64::from_le_bytes(m);
            if blob_len > MAX_BLOB {
                return Err(too_long("blob", blob_len));
            }
            let mut blob = vec![0u8; blob_len as usize];
            self.from.read_exact(&mut blob)?;
            Ok((h, blob))
        };
        let (h, blob) = match read() {
            Ok(x) => x,
            Err(e) => return Err(self.died(format!("no answer to the {op} request: {e}"))),
        };
        let header: serde_json::Value = serde_json::from_slice(&h)
            .map_err(|e| BlenderError::Answer(format!("a header that is not JSON ({e})")))?;
        if header["ok"].as_bool() != Some(true) {
            return Err(BlenderError::Refused {
                op: op.to_string(),
                error: header["error"].as_str().unwrap_or("no reason given").into(),
            });
        }
        Ok((header, blob))
    }

    fn died(&mut self, why: String) -> BlenderError {
        // Let the process end and the standard error reader catch its last lines.
        std::thread::sleep(std::time::Duration::from_millis(100));
        let status = self
            .child
            .try_wait()
            .ok()
            .flatten()
            .map(|s| format!(", {s}"))
            .unwrap_or_default();
        let tail = self.tail.lock().unwrap_or_else(|p| p.into_inner());
        BlenderError::Died {
            why: why + &status,
            tail: tail.iter().cloned().collect::<Vec<_>>().join("\n"),
        }
    }
}

impl Drop for Worker {
    fn drop(&mut self) {
        let quit = br#"{"op":"quit"}"#;
        let _ = self
            .to
            .write_all(&(quit.len() as u32).to_le_bytes())
            .and_then(|_| self.to.write_all(quit))
            .and_then(|_| self.to.write_all(&0u64.to_le_bytes()))
            .and_then(|_| self.to.flush());
        for _ in 0..50 {
            if let Ok(Some(_)) = self.child.try_wait() {
                return;
            }
            std::thread::sleep(std::time::Duration::from_millis(20));
        }
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}
