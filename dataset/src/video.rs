//! Camera streams to video files through Debian's `ffmpeg`: raw RGB frames piped in, AV1 with
//! LeRobot's defaults (`libsvtav1`, `yuv420p`, keyframe every 2 frames, CRF 30) or H.264
//! (`libx264`, the same GOP), at a constant frame rate so that frame i sits at exactly i/fps.
//!
//! SVT-AV1 runs at preset 12 (LeRobot leaves the preset to the encoder's default, 10): on a
//! thermal-cycler episode at 224x224 it encodes 2.4x faster (145 against 60 frames/s per core)
//! for 0.1 dB less PSNR (46.6 against 46.7 dB) and 7% larger files; at preset 10 encoding took
//! four times as long as simulating and rendering together.
//!
//! It does not decide file names or layouts (the writers do).

use crate::DatasetError;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::{Child, ChildStdin, Command, Stdio};

#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Codec {
    /// AV1 through libsvtav1: LeRobot's default.
    Av1,
    /// H.264 through libx264.
    H264,
}

impl Codec {
    /// The codec's name as PyAV reports it (LeRobot's `video.codec`).
    pub fn name(self) -> &'static str {
        match self {
            Codec::Av1 => "av1",
            Codec::H264 => "h264",
        }
    }

    fn args(self) -> &'static [&'static str] {
        match self {
            Codec::Av1 => &["-c:v", "libsvtav1", "-crf", "30", "-preset", "12"],
            Codec::H264 => &[
                "-c:v", "libx264", "-crf", "23", "-preset", "fast", "-bf", "0",
            ],
        }
    }
}

/// One video being written.
pub(crate) struct VideoWriter {
    child: Child,
    stdin: Option<ChildStdin>,
    path: PathBuf,
    width: usize,
    height: usize,
    pub frames: usize,
}

impl VideoWriter {
    pub(crate) fn create(
        path: &Path,
        width: usize,
        height: usize,
        fps: u32,
        codec: Codec,
    ) -> Result<VideoWriter, DatasetError> {
        let size = format!("{width}x{height}");
        let rate = fps.to_string();
        let mut cmd = Command::new("ffmpeg");
        cmd.args(["-hide_banner", "-loglevel", "error", "-y", "-f", "rawvideo"])
            .args(["-pix_fmt", "rgb24", "-s", &size, "-r", &rate, "-i", "-"])
            .args(codec.args())
            .args(["-pix_fmt", "yuv420p", "-g", "2", "-r", &rate])
            // Reproducible files: no encoder version or creation time in the container.
            .args(["-fflags", "+bitexact", "-map_metadata", "-1"])
            .arg(path)
            .stdin(Stdio::piped())
            .stdout(Stdio::null())
            .stderr(Stdio::piped());
        let mut child = cmd.spawn().map_err(|e| DatasetError::Ffmpeg {
            path: path.to_path_buf(),
            why: format!("cannot start ffmpeg (run `make setup`): {e}"),
        })?;
        let stdin = child.stdin.take();
        Ok(VideoWriter {
            child,
            stdin,
            path: path.to_path_buf(),
            width,
            height,
            frames: 0,
        })
    }

    pub(crate) fn push(&mut self, rgb: &[u8]) -> Result<(), DatasetError> {
        assert_eq!(rgb.len(), self.width * self.height * 3, "frame size");
        let stdin = self.stdin.as_mut().expect("open until finish");
        if let Err(e) = stdin.write_all(rgb) {
            return Err(self.failed(format!("writing a frame: {e}")));
        }
        self.frames += 1;
        Ok(())
    }

    fn failed(&mut self, why: String) -> DatasetError {
        self.stdin.take();
        let mut err = String::new();
        if let Some(mut e) = self.child.stderr.take() {
            std::io::Read::read_to_string(&mut e, &mut err).ok();
        }
        self.child.wait().ok();
        DatasetError::Ffmpeg {
            path: self.path.clone(),
            why: format!("{why} {}", err.trim()),
        }
    }

    /// Closes the stream and waits for the file.
    pub(crate) fn finish(mut self) -> Result<usize, DatasetError> {
        self.stdin.take();
        let out = self
            .child
            .wait_with_output()
            .map_err(|e| DatasetError::Ffmpeg {
                path: self.path.clone(),
                why: e.to_string(),
            })?;
        if !out.status.success() {
            return Err(DatasetError::Ffmpeg {
                path: self.path.clone(),
                why: String::from_utf8_lossy(&out.stderr).trim().to_string(),
            });
        }
        Ok(self.frames)
    }
}

/// Joins videos of the same codec, size and rate into one, copying streams (LeRobot v3.0's
/// shared files).
pub(crate) fn concatenate(parts: &[PathBuf], out: &Path) -> Result<(), DatasetError> {
    let list = out.with_extension("txt");
    // Absolute: ffmpeg resolves a list's relative names against the list's own folder.
    let mut text = String::new();
    for p in parts {
        let p = std::path::absolute(p).map_err(|e| DatasetError::io("resolve", p, e))?;
        text += &format!(
            "file '{}'\n",
            p.display().to_string().replace('\'', "'\\''")
        );
    }
    std::fs::write(&list, text).map_err(|e| DatasetError::io("write", &list, e))?;
    let status = Command::new("ffmpeg")
        .args([
            "-hide_banner",
            "-loglevel",
            "error",
            "-y",
            "-f",
            "concat",
            "-safe",
            "0",
        ])
        .arg("-i")
        .arg(&list)
        .args(["-c", "copy", "-fflags", "+bitexact", "-map_metadata", "-1"])
        .arg(out)
        .status()
        .map_err(|e| DatasetError::Ffmpeg {
            path: out.to_path_buf(),
            why: e.to_string(),
        })?;
    std::fs::remove_file(&list).ok();
    if !status.success() {
        return Err(DatasetError::Ffmpeg {
            path: out.to_path_buf(),
            why: format!("concatenation failed ({status})"),
        });
    }
    Ok(())
}
