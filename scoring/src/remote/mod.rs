//! Models over the network: a [`Model`] is one connection to a model server speaking one
//! [`Wire`] protocol under one [`results::profile::Profile`]; a [`ModelPolicy`] drives one episode
//! through it (observation in the profile's layout out, an action chunk back, the first
//! `execute` actions run). The connection is kept across episodes and reopened, with backoff,
//! after a failure.
//!
//! Wires:
//! - `openpi`: openpi's websocket protocol with msgpack-numpy (binary marker keys). A metadata
//!   frame on connect is read when the server sends one (openpi) and not waited for when it does
//!   not (AutoBio's variant); the reply's `actions` or `action` key; a text frame is the server's
//!   error. With the profile's `reset_frame`, `{"reset": true, "task": {...}}` precedes each
//!   episode (no reply).
//! - `vla-eval`: allenai's evaluation harness frames (`{type, payload, seq, timestamp}`, `hello`
//!   handshake, `episode_start`/`episode_end`, replies echoing `seq`, `__image__` images). Its
//!   servers keep the chunk and answer one action per observation; a chunk is accepted too.
//!
//! Failures of the server (no connection, closed, silent past the timeout, error frames, frames
//! that do not decode or break the wire's framing) are [`policy::PolicyError::Server`]; decodable
//! replies without usable actions (no `actions` key, wrong shape or dtype) are
//! [`policy::PolicyError::BadActions`]. It does not render or step the simulation.

pub mod codec;
mod link;

use codec::Keys;
pub use link::{Frame, Link};
use policy::WireError;
use policy::{Needs, Observation, Policy, PolicyError};
use results::profile::{ImageEncoding, Layout, LoadedProfile};
use rmpv::Value;
use std::time::{Duration, Instant, SystemTime, UNIX_EPOCH};

use results::run::record::Wire;

/// How long a fresh openpi connection waits for the server's metadata frame before taking the
/// server for one that sends none (a late one is still recognised).
const METADATA_WAIT: Duration = Duration::from_millis(500);

/// One model server connection.
pub struct Model {
    link: Link,
    pub wire: Wire,
    pub profile: LoadedProfile,
    /// What the server said about itself: openpi's metadata frame, vla-eval's `hello` reply.
    pub metadata: Option<serde_json::Value>,
    seq: u64,
    /// Whether the current connection's metadata frame is still to come (openpi).
    metadata_pending: bool,
}

/// What a model is told about an episode when it starts.
pub struct EpisodeInfo<'a> {
    pub task_id: &'a str,
    pub seed: u64,
    pub instruction: &'a str,
}

impl Model {
    pub fn new(url: &str, wire: Wire, profile: LoadedProfile) -> Result<Model, WireError> {
        let timeout = Duration::from_secs_f64(profile.profile.timeout_s);
        Ok(Model {
            link: Link::new(url, timeout)?,
            wire,
            profile,
            metadata: None,
            seq: 0,
            metadata_pending: false,
        })
    }

    pub fn url(&self) -> &str {
        &self.link.url
    }

    /// Connection attempts and the first retry's wait (doubled per retry).
    pub fn set_retries(&mut self, attempts: u32, backoff: Duration) {
        self.link.attempts = attempts;
        self.link.backoff = backoff;
    }

    /// Connects (if not connected) and greets the server: reads openpi's metadata frame, or
    /// exchanges vla-eval's `hello`.
    pub fn open(&mut self) -> Result<(), WireError> {
        if !self.link.ensure_open()? {
            return Ok(());
        }
        match self.wire {
            Wire::Openpi => {
                self.metadata_pending = true;
                match self.link.try_recv(METADATA_WAIT)? {
                    Some(Frame::Binary(b)) => {
                        self.take_metadata(&b)?;
                    }
                    Some(Frame::Text(t)) => return self.error_frame(t),
                    None => {}
                }
            }
            Wire::VlaEval => {
                let payload = codec::map(vec![
                    (
                        "harness_version",
                        codec::str(concat!("autobio ", env!("CARGO_PKG_VERSION"))),
                    ),
                    ("protocol_version", Value::from(1u64)),
                    ("benchmark", codec::str("autobio")),
                ]);
                let deadline = self.link.deadline();
                let seq = self.send_frame("hello", payload, deadline)?;
                let (kind, payload) = self.recv_frame(seq, deadline)?;
                if kind != "hello" {
                    self.link.drop_connection();
                    return Err(WireError::Malformed(format!(
                        "expected the server's `hello`, got `{kind}`"
                    )));
                }
                self.metadata = Some(codec::to_json(&payload));
            }
        }
        Ok(())
    }

    fn take_metadata(&mut self, bytes: &[u8]) -> Result<(), WireError> {
        let v = codec::decode(bytes).map_err(|e| self.malformed(e.to_string()))?;
        self.metadata = Some(codec::to_json(&v));
        self.metadata_pending = false;
        Ok(())
    }

    fn malformed(&mut self, why: String) -> WireError {
        self.link.drop_connection();
        WireError::Malformed(why)
    }

    fn error_frame<T>(&mut self, text: String) -> Result<T, WireError> {
        // openpi closes the connection after its error frame.
        if self.wire == Wire::Openpi {
            self.link.drop_connection();
        }
        let first: String = text
            .trim()
            .lines()
            .last()
            .unwrap_or("")
            .chars()
            .take(400)
            .collect();
        Err(WireError::ErrorFrame(first))
    }

    fn send_frame(
        &mut self,
        kind: &str,
        payload: Value,
        deadline: Instant,
    ) -> Result<u64, WireError> {
        self.seq += 1;
        let now = SystemTime::now()
            .duration_since(UNIX_EPOCH)
            .map(|d| d.as_secs_f64())
            .unwrap_or(0.0);
        let msg = codec::map(vec![
            ("type", codec::str(kind)),
            ("payload", payload),
            ("seq", Value::from(self.seq)),
            ("timestamp", Value::F64(now)),
        ]);
        self.link.send_by(codec::encode(&msg), deadline)?;
        Ok(self.seq)
    }

    /// A vla-eval frame answering `seq`: its type and payload; an `error` frame is an error. An
    /// error answering an earlier frame (vla-eval answers a failed `episode_start` so) is
    /// remembered and reported once the reply to `seq` has been read, so that it fails the
    /// episode it belongs to and leaves no stale reply behind. Every frame read on the way
    /// counts against the exchange's one `deadline`.
    fn recv_frame(&mut self, seq: u64, deadline: Instant) -> Result<(String, Value), WireError> {
        let mut earlier: Option<String> = None;
        loop {
            let bytes = match self.link.recv_by(deadline)? {
                Frame::Binary(b) => b,
                Frame::Text(t) => return self.error_frame(t),
            };
            let v = codec::decode(&bytes).map_err(|e| self.malformed(e.to_string()))?;
            let field = |k: &str| codec::get(&v, k).cloned();
            let (Some(kind), Some(payload), Some(echo)) =
                (field("type"), field("payload"), field("seq"))
            else {
                return Err(self.malformed("a frame without `type`, `payload` and `seq`".into()));
            };
            let kind = kind.as_str().unwrap_or_default().to_string();
            let answers = echo.as_u64() == Some(seq);
            if kind == "error" {
                let why = codec::get(&payload, "error")
                    .and_then(|e| e.as_str().map(str::to_string))
                    .unwrap_or_else(|| codec::to_json(&payload).to_string());
                if answers {
                    // An earlier error (a failed `episode_start`) is the cause of this one.
                    return self.error_frame(earlier.unwrap_or(why));
                }
                earlier.get_or_insert(why);
                continue;
            }
            if !answers {
                return Err(self.malformed(format!(
                    "the reply to frame {seq} carries seq {echo}; replies must echo their request's seq"
                )));
            }
            if let Some(why) = earlier {
                return self.error_frame(why);
            }
            return Ok((kind, payload));
        }
    }

    /// Tells the server an episode starts.
    pub fn start_episode(&mut self, info: &EpisodeInfo) -> Result<(), WireError> {
        self.drop_if_stale();
        self.open()?;
        let task = codec::map(vec![
            ("name", codec::str(info.task_id)),
            ("id", codec::str(info.task_id)),
            ("seed", Value::from(info.seed)),
            ("instruction", codec::str(info.instruction)),
        ]);
        match self.wire {
            Wire::Openpi if self.profile.profile.reset_frame => {
                let msg = codec::map(vec![("reset", Value::Boolean(true)), ("task", task)]);
                self.link.send(codec::encode(&msg))
            }
            Wire::Openpi => Ok(()),
            Wire::VlaEval => {
                let deadline = self.link.deadline();
                self.send_frame("episode_start", codec::map(vec![("task", task)]), deadline)
                    .map(|_| ())
            }
        }
    }

    /// Drops a kept connection the server has closed since the last episode (a restart, a
    /// keepalive timeout), so that the episode starts on a fresh one instead of failing at its
    /// first query. A frame waiting there is a late openpi metadata frame, or a sign the
    /// connection's state is unknown.
    fn drop_if_stale(&mut self) {
        if !self.link.is_open() {
            return;
        }
        match self.link.try_recv(Duration::from_millis(1)) {
            Ok(None) => {}
            Ok(Some(Frame::Binary(b))) if self.wire == Wire::Openpi && self.metadata_pending => {
                if self.take_metadata(&b).is_err() {
                    self.link.drop_connection();
                }
            }
            Ok(Some(_)) => self.link.drop_connection(),
            Err(_) => {}
        }
    }

    /// Tells the server how the episode ended (vla-eval); failures here change nothing.
    pub fn end_episode(&mut self, success: bool, steps: u64) {
        if self.wire == Wire::VlaEval && self.link.is_open() {
            let payload = codec::map(vec![
                (
                    "metrics",
                    codec::map(vec![("success", Value::Boolean(success))]),
                ),
                ("steps", Value::from(steps)),
            ]);
            let deadline = self.link.deadline();
            self.send_frame("episode_end", payload, deadline).ok();
        }
    }

    /// One query: the observation (in the wire's layout) out, the action rows back. A reply
    /// that decodes but holds no usable actions is [`PolicyError::BadActions`].
    fn infer(&mut self, obs: Value) -> Result<Vec<Vec<f64>>, PolicyError> {
        self.open().map_err(PolicyError::Server)?;
        let reply = match self.wire {
            Wire::Openpi => self.openpi_reply(obs).map_err(PolicyError::Server)?,
            Wire::VlaEval => {
                let deadline = self.link.deadline();
                let seq = self
                    .send_frame("observation", obs, deadline)
                    .map_err(PolicyError::Server)?;
                let (kind, payload) = self
                    .recv_frame(seq, deadline)
                    .map_err(PolicyError::Server)?;
                if kind != "action" {
                    return Err(PolicyError::Server(
                        self.malformed(format!("expected an `action` frame, got `{kind}`")),
                    ));
                }
                payload
            }
        };
        let Some(actions) = codec::get(&reply, "actions").or_else(|| codec::get(&reply, "action"))
        else {
            return Err(PolicyError::BadActions(format!(
                "the reply has no `actions` (nor `action`) key: {}",
                short(&codec::to_json(&reply).to_string())
            )));
        };
        codec::actions(actions).map_err(|e| PolicyError::BadActions(e.to_string()))
    }

    /// openpi: the observation out, its reply back (a metadata frame met on the way is kept),
    /// all within one timeout.
    fn openpi_reply(&mut self, obs: Value) -> Result<Value, WireError> {
        let deadline = self.link.deadline();
        self.link.send_by(codec::encode(&obs), deadline)?;
        let mut took_metadata = false;
        loop {
            let frame = match self.link.recv_by(deadline) {
                // We took a reply without actions for a late metadata frame: it was the reply.
                Err(WireError::Timeout(_)) if took_metadata => {
                    return Err(WireError::Malformed(
                        "the first reply had no `actions` (nor `action`) key".into(),
                    ));
                }
                other => other?,
            };
            let bytes = match frame {
                Frame::Binary(b) => b,
                Frame::Text(t) => return self.error_frame(t),
            };
            let v = codec::decode(&bytes).map_err(|e| self.malformed(e.to_string()))?;
            let has_actions =
                codec::get(&v, "actions").is_some() || codec::get(&v, "action").is_some();
            if !has_actions && self.metadata_pending {
                // A metadata frame that came after we stopped waiting for it.
                self.take_metadata(&bytes)?;
                took_metadata = true;
                continue;
            }
            self.metadata_pending = false;
            return Ok(v);
        }
    }

    /// The observation in this wire's and profile's layout.
    fn observation(&self, obs: &Observation, layout: &Layout) -> Value {
        let p = &self.profile.profile;
        let state = p.to_model(&obs.state);
        let keys = match self.wire {
            Wire::Openpi => Keys::Binary,
            Wire::VlaEval => Keys::Text,
        };
        let image = |img: Option<&results::Image>| match img {
            None => Value::Nil,
            Some(i) => match self.wire {
                Wire::Openpi => codec::image_array(keys, &i.rgb, i.width, i.height),
                Wire::VlaEval => codec::image_vla_eval(
                    &i.rgb,
                    i.width,
                    i.height,
                    p.image_encoding == ImageEncoding::Png,
                ),
            },
        };
        let mut images: Vec<(&str, Value)> = Vec::new();
        for (im, cam) in p.images.iter().zip(&layout.cameras) {
            images.push((&im.key, image(cam.and_then(|c| obs.images.get(c)))));
            if let Some(prev) = &im.previous_key {
                images.push((prev, image(cam.and_then(|c| obs.previous.get(c)))));
            }
        }
        let state = codec::floats(keys, &state, p.state_dtype);
        // Opt-in (the profile's `environment_state_key`): the task's environment state, as
        // float32 or float64 like the robot state.
        let environment = p.environment_state_key.as_deref().map(|key| {
            (
                key,
                codec::floats(keys, &obs.environment_state, p.state_dtype),
            )
        });
        match self.wire {
            Wire::Openpi => {
                let mut m = vec![(p.state_key.as_str(), state)];
                m.extend(environment);
                m.extend(images);
                m.push((p.prompt_key.as_str(), codec::str(obs.prompt)));
                codec::map(m)
            }
            Wire::VlaEval => {
                let mut m = vec![("images", codec::map(images)), ("states", state)];
                m.extend(environment);
                m.push(("task_description", codec::str(obs.prompt)));
                codec::map(m)
            }
        }
    }
}

fn short(s: &str) -> String {
    if s.len() <= 200 {
        return s.to_string();
    }
    let cut = (0..=200)
        .rev()
        .find(|&i| s.is_char_boundary(i))
        .unwrap_or(0);
    format!("{}...", &s[..cut])
}

/// One episode of a model: observations out, chunks back, the first `execute` of each run.
pub struct ModelPolicy<'m> {
    model: &'m mut Model,
    layout: Layout,
}

impl<'m> ModelPolicy<'m> {
    /// Starts an episode on the server (connecting if needed).
    pub fn start(
        model: &'m mut Model,
        layout: Layout,
        info: &EpisodeInfo,
    ) -> Result<ModelPolicy<'m>, PolicyError> {
        model.start_episode(info).map_err(PolicyError::Server)?;
        Ok(ModelPolicy { model, layout })
    }
}

impl Policy for ModelPolicy<'_> {
    fn name(&self) -> String {
        format!(
            "model {} ({}, {})",
            self.model.url(),
            self.model.wire,
            self.model.profile.profile.name
        )
    }

    fn needs(&self) -> Needs {
        let p = &self.model.profile.profile;
        Needs {
            image_size: (!p.images.is_empty()).then_some(p.image_size),
            history_steps: p.history_steps,
            environment_state: p.environment_state_key.is_some(),
        }
    }

    fn act(&mut self, obs: &Observation) -> Result<Vec<Vec<f64>>, PolicyError> {
        let value = self.model.observation(obs, &self.layout);
        let rows = self.model.infer(value)?;
        let p = &self.model.profile.profile;
        let len = self.layout.state_len;
        if rows.is_empty() {
            return Err(PolicyError::BadActions("an empty action chunk".into()));
        }
        if rows.len() > p.chunk {
            return Err(PolicyError::BadActions(format!(
                "a chunk of {} actions; the profile allows at most {}",
                rows.len(),
                p.chunk
            )));
        }
        rows.iter()
            .take(p.execute)
            .map(|r| {
                p.from_model(r, len).ok_or_else(|| {
                    PolicyError::BadActions(format!(
                        "actions of {} values; this task's actions have {}",
                        r.len(),
                        p.action_dim(len)
                    ))
                })
            })
            .collect()
    }

    fn end_episode(&mut self, success: bool, steps: u64) {
        self.model.end_episode(success, steps);
    }
}
