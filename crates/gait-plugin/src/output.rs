//! Copies what a plugin returns into owned gait types, checking every count,
//! size and value first. Nothing is read past a length the checks accepted,
//! and a bad output is refused whole with a message saying what was wrong.

use gait_core::{CANONICAL, EdgeMap, Frame, Keypoint, Pose, Resize};
use image::{GrayImage, RgbImage};

use crate::abi::{GaitEdgeMaps, GaitImage, GaitImages, GaitPoses, GaitResize, GaitStrs};
use crate::library::copy_bytes;

/// Most keypoints per pose and longest keypoint name a plugin may return.
const MAX_KEYPOINTS: usize = 4096;
const MAX_NAME: usize = 256;

/// Borrows `count` items of a plugin array.
///
/// # Safety
/// `ptr` points to `count` readable items, or `count == 0`.
unsafe fn items<'a, X>(ptr: *const X, count: usize, what: &str) -> Result<&'a [X], String> {
    if count == 0 {
        return Ok(&[]);
    }
    if ptr.is_null() {
        return Err(format!("{what}: null pointer with {count} items"));
    }
    if !ptr.is_aligned() {
        return Err(format!("{what}: misaligned pointer"));
    }
    if count
        .checked_mul(size_of::<X>())
        .is_none_or(|b| b > isize::MAX as usize)
    {
        return Err(format!("{what}: impossible count {count}"));
    }
    // SAFETY: per the contract above; non-null, aligned, size fits isize.
    Ok(unsafe { std::slice::from_raw_parts(ptr, count) })
}

/// Copies an image buffer after checking `len == width * height * channels`.
///
/// # Safety
/// `image.data` points to `image.len` readable bytes.
unsafe fn pixels(image: &GaitImage, channels: u32, what: &str) -> Result<Vec<u8>, String> {
    let shape = format!(
        "{what}: {}x{} with {} channels",
        image.width, image.height, image.channels
    );
    if image.channels != channels {
        return Err(format!("{shape}, expected {channels} channels"));
    }
    if image.width == 0 || image.height == 0 {
        return Err(format!("{shape}: empty image"));
    }
    let expected = (image.width as usize)
        .checked_mul(image.height as usize)
        .and_then(|n| n.checked_mul(channels as usize));
    if expected != Some(image.len) {
        return Err(format!(
            "{shape} needs {} bytes, but the buffer has {}",
            expected.map_or_else(|| "more than usize::MAX".to_string(), |n| n.to_string()),
            image.len
        ));
    }
    // SAFETY: per the contract above.
    Ok(unsafe { items(image.data, image.len, what) }?.to_vec())
}

fn resize(
    r: &GaitResize,
    frame: &Frame,
    width: u32,
    height: u32,
    what: &str,
) -> Result<Resize, String> {
    if (r.src_width, r.src_height) != (frame.width(), frame.height()) {
        return Err(format!(
            "{what}: resize source {}x{} is not the frame's size {}x{}",
            r.src_width,
            r.src_height,
            frame.width(),
            frame.height()
        ));
    }
    if (r.dst_width, r.dst_height) != (width, height) {
        return Err(format!(
            "{what}: resize target {}x{} is not the edge map's size {width}x{height}",
            r.dst_width, r.dst_height
        ));
    }
    let scales_ok = [r.scale_x, r.scale_y]
        .iter()
        .all(|s| s.is_finite() && *s > 0.0);
    if !scales_ok || !r.offset_x.is_finite() || !r.offset_y.is_finite() {
        return Err(format!(
            "{what}: resize scale ({}, {}) and offset ({}, {}) must be finite, scales positive",
            r.scale_x, r.scale_y, r.offset_x, r.offset_y
        ));
    }
    Ok(Resize {
        src_width: r.src_width,
        src_height: r.src_height,
        dst_width: r.dst_width,
        dst_height: r.dst_height,
        scale_x: r.scale_x,
        scale_y: r.scale_y,
        offset_x: r.offset_x,
        offset_y: r.offset_y,
    })
}

fn count_matches(count: usize, frames: usize, what: &str) -> Result<(), String> {
    if count == frames {
        Ok(())
    } else {
        Err(format!("{count} {what} for {frames} frames"))
    }
}

/// One edge map per frame, gray, with a resize from the frame onto it.
///
/// # Safety
/// `out` was filled by the plugin with OK status and not yet released.
pub(crate) unsafe fn edge_maps(
    out: &GaitEdgeMaps,
    frames: &[Frame],
) -> Result<Vec<EdgeMap>, String> {
    count_matches(out.count, frames.len(), "edge maps")?;
    // SAFETY: per the contract above.
    let raw = unsafe { items(out.items, out.count, "edge maps") }?;
    raw.iter()
        .zip(frames)
        .enumerate()
        .map(|(i, (m, frame))| {
            let what = format!("edge map {i}");
            // SAFETY: per the contract above.
            let data = unsafe { pixels(&m.image, 1, &what) }?;
            let resize = resize(&m.resize, frame, m.image.width, m.image.height, &what)?;
            let image = GrayImage::from_raw(m.image.width, m.image.height, data)
                .ok_or_else(|| format!("{what}: buffer does not fit"))?;
            Ok(EdgeMap {
                index: frame.index,
                image,
                resize,
            })
        })
        .collect()
}

/// One RGB image per frame, each of its frame's size.
///
/// # Safety
/// `out` was filled by the plugin with OK status and not yet released.
pub(crate) unsafe fn images(out: &GaitImages, frames: &[Frame]) -> Result<Vec<Frame>, String> {
    count_matches(out.count, frames.len(), "images")?;
    // SAFETY: per the contract above.
    let raw = unsafe { items(out.items, out.count, "images") }?;
    raw.iter()
        .zip(frames)
        .enumerate()
        .map(|(i, (img, frame))| {
            let what = format!("image {i}");
            // SAFETY: per the contract above.
            let data = unsafe { pixels(img, 3, &what) }?;
            if (img.width, img.height) != (frame.width(), frame.height()) {
                return Err(format!(
                    "{what} is {}x{}, but its frame is {}x{} (regenerated frames keep their size)",
                    img.width,
                    img.height,
                    frame.width(),
                    frame.height()
                ));
            }
            let image = RgbImage::from_raw(img.width, img.height, data)
                .ok_or_else(|| format!("{what}: buffer does not fit"))?;
            Ok(Frame::new(frame.index, image))
        })
        .collect()
}

/// One pose per frame with one `(x, y, likelihood)` per name. Found keypoints
/// have finite coordinates and a likelihood in [0, 1]; `(NaN, NaN, 0)` is a
/// missing keypoint; anything else is refused.
///
/// # Safety
/// `out` was filled by the plugin with OK status and not yet released.
pub(crate) unsafe fn poses(
    out: &GaitPoses,
    frames: &[Frame],
    names: &[String],
) -> Result<Vec<Pose>, String> {
    count_matches(out.poses, frames.len(), "poses")?;
    if out.poses > 0 && out.keypoints != names.len() {
        return Err(format!(
            "{} keypoints per pose, but the plugin names {}",
            out.keypoints,
            names.len()
        ));
    }
    let expected = out
        .poses
        .checked_mul(out.keypoints)
        .and_then(|n| n.checked_mul(3));
    if expected != Some(out.len) {
        return Err(format!(
            "{} values for {} poses of {} keypoints (expected 3 per keypoint)",
            out.len, out.poses, out.keypoints
        ));
    }
    // SAFETY: per the contract above.
    let values = unsafe { items(out.values, out.len, "pose values") }?;
    let mut poses = Vec::with_capacity(out.poses);
    // Zero poses come with zero values; `max(1)` only keeps chunks_exact legal.
    for (p, frame) in values.chunks_exact(3 * out.keypoints.max(1)).zip(frames) {
        let keypoints = p
            .chunks_exact(3)
            .zip(names)
            .map(|(v, name)| keypoint(v[0], v[1], v[2], name, frame.index))
            .collect::<Result<Vec<_>, String>>()?;
        poses.push(Pose { keypoints });
    }
    Ok(poses)
}

fn keypoint(x: f64, y: f64, likelihood: f64, name: &str, frame: usize) -> Result<Keypoint, String> {
    if x.is_nan() && y.is_nan() && likelihood == 0.0 {
        return Ok(Keypoint::missing());
    }
    if x.is_finite() && y.is_finite() && (0.0..=1.0).contains(&likelihood) {
        return Ok(Keypoint::new(x, y, likelihood));
    }
    Err(format!(
        "keypoint `{name}` of frame {frame} is ({x}, {y}, {likelihood}); found keypoints need finite coordinates and a likelihood in [0, 1], missing ones are (NaN, NaN, 0)"
    ))
}

/// Keypoint names: UTF-8, non-empty, unique, starting with the canonical names.
///
/// # Safety
/// `out` was filled by the plugin with OK status and not yet released.
pub(crate) unsafe fn names(out: &GaitStrs) -> Result<Vec<String>, String> {
    if out.count > MAX_KEYPOINTS {
        return Err(format!(
            "{} keypoint names (at most {MAX_KEYPOINTS})",
            out.count
        ));
    }
    // SAFETY: per the contract above.
    let raw = unsafe { items(out.items, out.count, "keypoint names") }?;
    let mut names: Vec<String> = Vec::with_capacity(raw.len());
    for (i, s) in raw.iter().enumerate() {
        if s.len > MAX_NAME {
            return Err(format!(
                "keypoint name {i} is {} bytes long (at most {MAX_NAME})",
                s.len
            ));
        }
        // SAFETY: per the contract above.
        let bytes = unsafe { copy_bytes(*s, MAX_NAME) }
            .ok_or_else(|| format!("keypoint name {i}: null pointer"))?;
        let name =
            String::from_utf8(bytes).map_err(|_| format!("keypoint name {i} is not UTF-8"))?;
        if name.trim().is_empty() {
            return Err(format!("keypoint name {i} is empty"));
        }
        if names.contains(&name) {
            return Err(format!("keypoint name `{name}` appears twice"));
        }
        names.push(name);
    }
    if names.len() < CANONICAL.len() || names.iter().zip(CANONICAL).any(|(n, c)| n != c) {
        return Err(format!(
            "keypoint names must start with the canonical names {} (missing parts stay (NaN, NaN, 0)); got {}",
            CANONICAL.join(", "),
            names.join(", ")
        ));
    }
    Ok(names)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn missing_and_found_keypoints() {
        assert!(
            !keypoint(f64::NAN, f64::NAN, 0.0, "nose", 0)
                .unwrap()
                .is_found()
        );
        assert_eq!(
            keypoint(1.0, 2.0, 0.5, "nose", 0).unwrap(),
            Keypoint::new(1.0, 2.0, 0.5)
        );
        for (x, y, l) in [
            (f64::NAN, 2.0, 0.5),
            (1.0, f64::INFINITY, 0.5),
            (1.0, 2.0, f64::NAN),
            (1.0, 2.0, 1.5),
            (f64::NAN, f64::NAN, 0.3),
        ] {
            let err = keypoint(x, y, l, "left_knee", 7).unwrap_err();
            assert!(
                err.contains("left_knee") && err.contains("frame 7"),
                "{err}"
            );
        }
    }

    #[test]
    fn image_size_is_checked_before_reading() {
        let buf = [0u8; 11];
        let img = GaitImage {
            data: buf.as_ptr(),
            len: buf.len(),
            width: 4,
            height: 3,
            channels: 1,
        };
        // SAFETY: `buf` has `len` bytes.
        let err = unsafe { pixels(&img, 1, "edge map 0") }.unwrap_err();
        assert!(
            err.contains("needs 12 bytes") && err.contains("has 11"),
            "{err}"
        );
        let huge = GaitImage {
            width: u32::MAX,
            height: u32::MAX,
            channels: 3,
            len: usize::MAX,
            ..img
        };
        // SAFETY: the size check fails before anything is read.
        assert!(unsafe { pixels(&huge, 3, "x") }.is_err());
    }
}
