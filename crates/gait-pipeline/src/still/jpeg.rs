//! JPEG decoding through libjpeg-turbo with the settings of OpenCV's `imread`
//! (accurate integer IDCT, smooth chroma upsampling: libjpeg's defaults, which
//! OpenCV 4.10 never changes), so the RGB is byte-identical to `cv2.imread`
//! and Pillow's. Two cases need more than TurboJPEG's RGB output:
//! - CMYK/YCCK files: TurboJPEG gives the (Adobe-inverted) CMYK values, turned
//!   into RGB with OpenCV's integer formula;
//! - a libjpeg warning (e.g. "Corrupt JPEG data: extraneous bytes before
//!   marker", common in camera files) is not fatal, as in OpenCV: the image is
//!   decoded and the warning returned. A file cut short ("Premature end of JPEG
//!   file") is refused, unlike OpenCV, which fills the missing part with grey:
//!   a half-grey frame would be analysed without anyone noticing.

use std::ffi::CStr;

use turbojpeg::raw;

/// A decoded JPEG, before EXIF orientation.
pub(crate) struct Decoded {
    pub width: u32,
    pub height: u32,
    pub rgb: Vec<u8>,
    /// libjpeg's warning, when it had one (the file is damaged but decodable).
    pub warning: Option<String>,
}

/// A TurboJPEG decompressor, destroyed on drop.
struct Handle(raw::tjhandle);

impl Drop for Handle {
    fn drop(&mut self) {
        // SAFETY: the handle came from tj3Init and is destroyed once.
        unsafe { raw::tj3Destroy(self.0) };
    }
}

impl Handle {
    fn new() -> Result<Self, String> {
        // SAFETY: tj3Init has no preconditions; a null result is checked.
        let h = unsafe { raw::tj3Init(raw::TJINIT_TJINIT_DECOMPRESS as i32) };
        if h.is_null() {
            return Err("libjpeg-turbo could not start".into());
        }
        Ok(Self(h))
    }

    fn error(&self) -> String {
        // SAFETY: tj3GetErrorStr returns a NUL-terminated string owned by the handle.
        let text = unsafe { CStr::from_ptr(raw::tj3GetErrorStr(self.0)) };
        text.to_string_lossy().into_owned()
    }

    fn get(&self, param: raw::TJPARAM) -> i32 {
        // SAFETY: a valid handle and a TurboJPEG parameter id.
        unsafe { raw::tj3Get(self.0, param as i32) }
    }
}

/// Width and height from the JPEG's header, without decoding it.
pub(crate) fn dimensions(data: &[u8]) -> Result<(u32, u32), String> {
    let h = Handle::new()?;
    header(&h, data)?;
    Ok(size(&h))
}

fn header(h: &Handle, data: &[u8]) -> Result<(), String> {
    // SAFETY: `data` is a valid slice for its length.
    let r = unsafe { raw::tj3DecompressHeader(h.0, data.as_ptr(), data.len() as _) };
    if r != 0 {
        return Err(h.error());
    }
    // Garbage after a JPEG signature can pass as a header with no frame in it.
    if size(h).0 == 0 || size(h).1 == 0 {
        return Err("no image size in its header".into());
    }
    Ok(())
}

fn size(h: &Handle) -> (u32, u32) {
    let w = h.get(raw::TJPARAM_TJPARAM_JPEGWIDTH).max(0) as u32;
    let ht = h.get(raw::TJPARAM_TJPARAM_JPEGHEIGHT).max(0) as u32;
    (w, ht)
}

/// Decodes `data` to RGB as `cv2.imread(IMREAD_COLOR)` does (before orientation).
pub(crate) fn decode(data: &[u8]) -> Result<Decoded, String> {
    let h = Handle::new()?;
    header(&h, data)?;
    let (width, height) = size(&h);
    let space = h.get(raw::TJPARAM_TJPARAM_COLORSPACE);
    let cmyk = space == raw::TJCS_TJCS_CMYK as i32 || space == raw::TJCS_TJCS_YCCK as i32;
    let (format, channels) = if cmyk {
        (raw::TJPF_TJPF_CMYK, 4)
    } else {
        (raw::TJPF_TJPF_RGB, 3)
    };
    let stride = width as usize * channels;
    let mut buf = vec![0u8; stride * height as usize];
    // SAFETY: `buf` holds `height` rows of `stride` bytes, as TurboJPEG writes for this format.
    let r = unsafe {
        raw::tj3Decompress8(
            h.0,
            data.as_ptr(),
            data.len() as _,
            buf.as_mut_ptr(),
            stride as i32,
            format,
        )
    };
    let mut warning = None;
    if r != 0 {
        // SAFETY: a valid handle.
        let code = unsafe { raw::tj3GetErrorCode(h.0) };
        let message = h.error();
        if code != raw::TJERR_TJERR_WARNING as i32 {
            return Err(message);
        }
        if message.contains("Premature end") {
            return Err(format!(
                "the file is cut short ({message}); copy or export it again"
            ));
        }
        warning = Some(message);
    }
    let rgb = if cmyk { cmyk_to_rgb(&buf) } else { buf };
    Ok(Decoded {
        width,
        height,
        rgb,
        warning,
    })
}

/// OpenCV's CMYK -> RGB on libjpeg's inverted CMYK: `R = K - ((255 - C) * K >> 8)`, alike for
/// G (M) and B (Y). Pillow rounds differently (`/ 255`): up to 2 levels apart.
fn cmyk_to_rgb(cmyk: &[u8]) -> Vec<u8> {
    cmyk.chunks_exact(4)
        .flat_map(|p| {
            let k = i32::from(p[3]);
            let f = |v: u8| (k - (((255 - i32::from(v)) * k) >> 8)) as u8;
            [f(p[0]), f(p[1]), f(p[2])]
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cmyk_white_black_and_a_colour() {
        // Inverted CMYK as libjpeg gives it: 255 is no ink.
        let px = [255, 255, 255, 255, 0, 0, 0, 0, 255, 0, 255, 255];
        assert_eq!(cmyk_to_rgb(&px), vec![255, 255, 255, 0, 0, 0, 255, 1, 255]);
    }

    #[test]
    fn not_a_jpeg_is_an_error_not_a_panic() {
        assert!(decode(b"\xff\xd8\xff\xe0 not really").is_err());
        assert!(decode(b"").is_err());
        assert!(dimensions(b"PNG").is_err());
    }
}
