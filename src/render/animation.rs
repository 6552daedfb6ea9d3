//! An animated GIF beside the rendered frames, so a run can be watched without a video tool.
//! Pure Rust (the `gif` crate's encoder, a NeuQuant palette per frame), and streamed: one frame
//! is decoded, quantised and written at a time, so memory stays at one frame however long the
//! run.

use std::fs::File;
use std::io::{BufReader, BufWriter, Write};
use std::path::{Path, PathBuf};

use super::RenderError;

/// NeuQuant's sampling factor: 1 is the best palette and slowest, 30 the fastest; 10 is the
/// `gif` crate's documented compromise between palette quality and time.
const QUANTISER_SPEED: i32 = 10;

/// Shortest frame delay in hundredths of a second: browsers and viewers slow anything
/// shorter down to 10 cs, so faster animations play at 50 frames per second.
pub const MIN_DELAY_CS: u16 = 2;

/// The delay between frames of an animation at `fps` frames per simulated second, in the
/// GIF's hundredths of a second, so that one simulated second plays in one second of real
/// time (slower above 50 fps, where the delay is [`MIN_DELAY_CS`]).
pub fn frame_delay(fps: f64) -> u16 {
    (100.0 / fps).round().clamp(f64::from(MIN_DELAY_CS), f64::from(u16::MAX)) as u16
}

/// Writes `out` (an endlessly looping GIF) from the PNG `frames` in order, each shown for
/// [`frame_delay`]`(fps)`. Nothing is written for no frames.
pub fn write_gif(frames: &[PathBuf], fps: f64, out: &Path) -> Result<(), RenderError> {
    let err = |path: &Path, reason: String| RenderError::Write { path: path.display().to_string(), reason };
    let Some(first) = frames.first() else { return Ok(()) };
    let (width, height, first_rgb) = read_rgb(first).map_err(|reason| err(first, reason))?;
    let (Ok(w), Ok(h)) = (u16::try_from(width), u16::try_from(height)) else {
        return Err(err(out, format!("a {width}x{height} frame is larger than a GIF can hold (65535x65535)")));
    };
    let tmp = out.with_extension("tmp.gif");
    let gif_err = |e: gif::EncodingError| err(&tmp, e.to_string());
    let file = File::create(&tmp).map_err(|e| err(&tmp, e.to_string()))?;
    let mut encoder = gif::Encoder::new(BufWriter::new(file), w, h, &[]).map_err(gif_err)?;
    encoder.set_repeat(gif::Repeat::Infinite).map_err(gif_err)?;
    // The first frame is decoded once: it gave the size and is the animation's first image.
    let rest = frames[1..].iter().map(|path| read_rgb(path).map(|f| (path, f)).map_err(|reason| err(path, reason)));
    for decoded in std::iter::once(Ok((first, (width, height, first_rgb)))).chain(rest) {
        let (path, (fw, fh, rgb)) = decoded?;
        if (fw, fh) != (width, height) {
            return Err(err(path, format!("is {fw}x{fh}, the first frame {width}x{height}")));
        }
        let mut frame = gif::Frame::from_rgb_speed(w, h, &rgb, QUANTISER_SPEED);
        frame.delay = frame_delay(fps);
        encoder.write_frame(&frame).map_err(gif_err)?;
    }
    // The trailer, then the whole file renamed into place: a GIF on disk is always complete.
    encoder.into_inner().map_err(gif_err)?.flush().map_err(|e| err(&tmp, e.to_string()))?;
    std::fs::rename(&tmp, out).map_err(|e| err(out, e.to_string()))
}

/// One 8-bit RGB (or RGBA, alpha dropped) PNG frame: width, height and the pixels.
fn read_rgb(path: &Path) -> Result<(u32, u32, Vec<u8>), String> {
    let file = File::open(path).map_err(|e| e.to_string())?;
    let mut decoder = png::Decoder::new(BufReader::new(file));
    decoder.set_transformations(png::Transformations::EXPAND | png::Transformations::STRIP_16);
    let mut reader = decoder.read_info().map_err(|e| e.to_string())?;
    let size = reader.output_buffer_size().ok_or("the frame is too large to decode")?;
    let mut buf = vec![0; size];
    let info = reader.next_frame(&mut buf).map_err(|e| e.to_string())?;
    buf.truncate(info.buffer_size());
    let rgb = match info.color_type {
        png::ColorType::Rgb => buf,
        png::ColorType::Rgba => buf.chunks_exact(4).flat_map(|p| [p[0], p[1], p[2]]).collect(),
        other => return Err(format!("frames are RGB images, this one is {other:?}")),
    };
    Ok((info.width, info.height, rgb))
}
