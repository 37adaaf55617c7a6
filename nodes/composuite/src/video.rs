//! Writing frames as a video file: GIF in-process (the `gif` crate, nothing else needed), MP4
//! (H.264) by piping raw RGB to an `ffmpeg` executable.
//!
//! Why ffmpeg for MP4 rather than an encoder in the build: the Rust ways to H.264 either
//! compile OpenH264's C++ sources into every build of this crate (minutes on a small machine,
//! for a feature most runs never use) or depend on young single-maintainer MP4 muxers. ffmpeg
//! is the tool everyone has or can get in one step (`apt-get install ffmpeg`; the
//! `imageio-ffmpeg` wheel ships a static one), its libx264 output plays everywhere, and the
//! GIF path stays free of it.

use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};
use std::process::{Child, ChildStdin, Command, Stdio};

/// What a video is written as, by its file's extension.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum VideoFormat {
    /// Animated GIF, 256 colours per frame, looping.
    Gif,
    /// H.264 in MP4 (yuv420p), through ffmpeg.
    Mp4,
}

impl VideoFormat {
    /// `gif` or `mp4`, case-insensitively.
    pub fn parse(name: &str) -> Result<VideoFormat, String> {
        match name.to_ascii_lowercase().as_str() {
            "gif" => Ok(VideoFormat::Gif),
            "mp4" => Ok(VideoFormat::Mp4),
            other => Err(format!("unknown video format `{other}`; valid: gif, mp4")),
        }
    }

    /// The format a path's extension names.
    pub fn of_path(path: &Path) -> Result<VideoFormat, String> {
        let ext = path.extension().and_then(|e| e.to_str()).unwrap_or("");
        VideoFormat::parse(ext).map_err(|_| {
            format!(
                "{}: a video file ends in .gif or .mp4 (the format follows the extension)",
                path.display()
            )
        })
    }

    /// The file extension.
    pub fn extension(self) -> &'static str {
        match self {
            VideoFormat::Gif => "gif",
            VideoFormat::Mp4 => "mp4",
        }
    }
}

/// Where to find ffmpeg: the given path, else `$COMPOSUITE_FFMPEG`, else `ffmpeg` on `PATH`.
pub fn find_ffmpeg(given: Option<&Path>) -> Result<PathBuf, String> {
    let named = given
        .map(Path::to_path_buf)
        .or_else(|| std::env::var_os("COMPOSUITE_FFMPEG").map(PathBuf::from));
    if let Some(path) = named {
        return if path.is_file() {
            Ok(path)
        } else {
            Err(format!("ffmpeg {}: no such file", path.display()))
        };
    }
    std::env::var_os("PATH")
        .iter()
        .flat_map(std::env::split_paths)
        .map(|dir| dir.join("ffmpeg"))
        .find(|p| p.is_file())
        .ok_or_else(|| {
            "writing .mp4 pipes the frames to ffmpeg, and none was found (--ffmpeg PATH, \
             $COMPOSUITE_FFMPEG, or `ffmpeg` on PATH): install it (`apt-get install ffmpeg`, \
             or `pip install imageio-ffmpeg`, whose binary \
             `python -c 'import imageio_ffmpeg; print(imageio_ffmpeg.get_ffmpeg_exe())'` \
             prints), or write a .gif, which needs nothing"
                .to_string()
        })
}

enum Sink {
    Gif(gif::Encoder<BufWriter<File>>),
    Ffmpeg {
        child: Child,
        stdin: Option<ChildStdin>,
    },
}

/// A video being written, one RGB frame (rows from the top, `rgb8`) at a time.
pub struct VideoWriter {
    sink: Sink,
    path: PathBuf,
    width: u32,
    height: u32,
    /// GIF frame delay (hundredths of a second).
    delay_cs: u16,
    frames: usize,
}

/// NeuQuant's sampling factor for GIF palettes (1 = best and slowest, 30 = fastest); 10 is
/// the `gif` crate's suggestion.
const GIF_QUANTIZER_SPEED: i32 = 10;

impl VideoWriter {
    /// Start writing `path` (must not exist) as `format`, `width` × `height` at `fps` frames per
    /// second. MP4 needs ffmpeg (see [`find_ffmpeg`]).
    pub fn create(
        path: &Path,
        format: VideoFormat,
        width: u32,
        height: u32,
        fps: f64,
        ffmpeg: Option<&Path>,
    ) -> Result<VideoWriter, String> {
        if path.exists() {
            return Err(format!(
                "{}: it exists already; give a new file (a video is never overwritten)",
                path.display()
            ));
        }
        if !(fps.is_finite() && fps > 0.0) {
            return Err(format!("frame rate {fps}: must be > 0"));
        }
        let sink = match format {
            VideoFormat::Gif => {
                let (w, h) = match (u16::try_from(width), u16::try_from(height)) {
                    (Ok(w), Ok(h)) => (w, h),
                    _ => {
                        return Err(format!(
                            "a GIF is at most 65535 pixels a side, not {width}×{height}"
                        ));
                    }
                };
                let file = File::create(path)
                    .map_err(|e| format!("cannot create {}: {e}", path.display()))?;
                let mut encoder = gif::Encoder::new(BufWriter::new(file), w, h, &[])
                    .map_err(|e| format!("{}: {e}", path.display()))?;
                encoder
                    .set_repeat(gif::Repeat::Infinite)
                    .map_err(|e| format!("{}: {e}", path.display()))?;
                Sink::Gif(encoder)
            }
            VideoFormat::Mp4 => {
                let ffmpeg = find_ffmpeg(ffmpeg)?;
                let mut child = Command::new(&ffmpeg)
                    .args(["-hide_banner", "-loglevel", "error", "-f", "rawvideo"])
                    .args(["-pix_fmt", "rgb24", "-s", &format!("{width}x{height}")])
                    .args(["-r", &format!("{fps}"), "-i", "-", "-an"])
                    // yuv420p (what players expect) needs even sides: pad odd ones by a pixel.
                    .args(["-vf", "pad=ceil(iw/2)*2:ceil(ih/2)*2"])
                    .args(["-c:v", "libx264", "-pix_fmt", "yuv420p"])
                    .args(["-movflags", "+faststart", "-n"])
                    .arg(path)
                    .stdin(Stdio::piped())
                    .stdout(Stdio::null())
                    .stderr(Stdio::piped())
                    .spawn()
                    .map_err(|e| format!("cannot run {}: {e}", ffmpeg.display()))?;
                let stdin = child.stdin.take();
                Sink::Ffmpeg { child, stdin }
            }
        };
        Ok(VideoWriter {
            sink,
            path: path.to_path_buf(),
            width,
            height,
            delay_cs: (100.0 / fps).round().clamp(1.0, f64::from(u16::MAX)) as u16,
            frames: 0,
        })
    }

    /// Append one frame: `width · height · 3` bytes of RGB.
    pub fn push(&mut self, rgb: &[u8]) -> Result<(), String> {
        let expected = self.width as usize * self.height as usize * 3;
        if rgb.len() != expected {
            return Err(format!(
                "a {}×{} frame has {expected} RGB bytes, not {}",
                self.width,
                self.height,
                rgb.len()
            ));
        }
        match &mut self.sink {
            Sink::Gif(encoder) => {
                let mut frame = gif::Frame::from_rgb_speed(
                    self.width as u16,
                    self.height as u16,
                    rgb,
                    GIF_QUANTIZER_SPEED,
                );
                frame.delay = self.delay_cs;
                encoder
                    .write_frame(&frame)
                    .map_err(|e| format!("{}: {e}", self.path.display()))?;
            }
            Sink::Ffmpeg { stdin, .. } => {
                let pipe = stdin.as_mut().expect("open until finish");
                pipe.write_all(rgb).map_err(|e| {
                    format!("ffmpeg stopped taking frames ({e}); see its message above")
                })?;
            }
        }
        self.frames += 1;
        Ok(())
    }

    /// Close the file; the number of frames written.
    pub fn finish(self) -> Result<usize, String> {
        match self.sink {
            Sink::Gif(encoder) => {
                let mut out = encoder
                    .into_inner()
                    .map_err(|e| format!("{}: {e}", self.path.display()))?;
                out.flush()
                    .map_err(|e| format!("{}: {e}", self.path.display()))?;
            }
            Sink::Ffmpeg { child, stdin } => {
                drop(stdin); // end of input: ffmpeg writes the file and exits
                let output = child
                    .wait_with_output()
                    .map_err(|e| format!("ffmpeg: {e}"))?;
                if !output.status.success() {
                    return Err(format!(
                        "ffmpeg failed writing {} ({}): {}",
                        self.path.display(),
                        output.status,
                        String::from_utf8_lossy(&output.stderr).trim()
                    ));
                }
            }
        }
        Ok(self.frames)
    }
}

#[cfg(test)]
mod test {
    use super::*;

    #[test]
    fn formats_follow_the_extension_and_bad_ones_are_named() {
        assert_eq!(
            VideoFormat::of_path(Path::new("a/ep.GIF")),
            Ok(VideoFormat::Gif)
        );
        assert_eq!(
            VideoFormat::of_path(Path::new("ep.mp4")),
            Ok(VideoFormat::Mp4)
        );
        let err = VideoFormat::of_path(Path::new("ep.avi")).unwrap_err();
        assert!(err.contains(".gif or .mp4"), "{err}");
        assert!(VideoFormat::parse("webm").unwrap_err().contains("gif, mp4"));
    }

    #[test]
    fn a_gif_holds_every_frame_pushed() {
        let dir = std::env::temp_dir().join(format!("video-test-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("t.gif");
        let _ = std::fs::remove_file(&path);
        let mut video = VideoWriter::create(&path, VideoFormat::Gif, 8, 6, 20.0, None).unwrap();
        for i in 0..5u8 {
            video.push(&[i * 40; 8 * 6 * 3]).unwrap();
        }
        assert!(video.push(&[0; 10]).unwrap_err().contains("144"));
        assert_eq!(video.finish().unwrap(), 5);
        let mut decoder = gif::DecodeOptions::new()
            .read_info(File::open(&path).unwrap())
            .unwrap();
        let mut frames = 0;
        while let Some(frame) = decoder.read_next_frame().unwrap() {
            assert_eq!((frame.width, frame.height, frame.delay), (8, 6, 5));
            frames += 1;
        }
        assert_eq!(frames, 5);
        let again = VideoWriter::create(&path, VideoFormat::Gif, 8, 6, 20.0, None);
        assert!(again.err().unwrap().contains("exists already"));
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
