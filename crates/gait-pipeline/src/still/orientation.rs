//! EXIF orientation as OpenCV's `imread` finds and applies it (loadsave.cpp,
//! exif.cpp in 4.10): only the file's first APP1 segment is read, its 6-byte
//! header skipped unchecked, then a TIFF header ("II" or "MM", 42) and tag
//! 0x0112 of IFD0; no tag or a value outside 1-8 means 1 (as stored).

use image::RgbImage;

/// The orientation value (1-8) of a JPEG file's first APP1 segment; 1 when none.
pub(crate) fn exif_orientation(jpeg: &[u8]) -> u16 {
    first_app1(jpeg).and_then(ifd0_orientation).unwrap_or(1)
}

/// The payload of the first APP1 marker segment before the image data.
fn first_app1(d: &[u8]) -> Option<&[u8]> {
    let mut i = 2;
    while i + 4 <= d.len() {
        if d[i] != 0xFF {
            i += 1;
            continue;
        }
        match d[i + 1] {
            // Fill bytes, and markers without a length.
            0xFF => i += 1,
            0x01 | 0xD0..=0xD8 => i += 2,
            // End of image or start of scan: no APP1 before the data.
            0xD9 | 0xDA => return None,
            m => {
                let len = usize::from(u16::from_be_bytes([d[i + 2], d[i + 3]]));
                if m == 0xE1 {
                    return d.get(i + 4..(i + 2 + len).min(d.len()));
                }
                i += 2 + len;
            }
        }
    }
    None
}

fn ifd0_orientation(app1: &[u8]) -> Option<u16> {
    let tiff = app1.get(6..)?;
    let little = match tiff.get(..2)? {
        b"II" => true,
        b"MM" => false,
        _ => return None,
    };
    let u16_at = |o: usize| {
        let b: [u8; 2] = tiff.get(o..o + 2)?.try_into().ok()?;
        Some(if little {
            u16::from_le_bytes(b)
        } else {
            u16::from_be_bytes(b)
        })
    };
    let u32_at = |o: usize| {
        let b: [u8; 4] = tiff.get(o..o + 4)?.try_into().ok()?;
        Some(if little {
            u32::from_le_bytes(b)
        } else {
            u32::from_be_bytes(b)
        })
    };
    if u16_at(2)? != 42 {
        return None;
    }
    let ifd = usize::try_from(u32_at(4)?).ok()?;
    let entries = usize::from(u16_at(ifd)?);
    (0..entries)
        .map(|k| ifd + 2 + 12 * k)
        .find(|&e| u16_at(e) == Some(0x0112))
        .and_then(|e| u16_at(e + 8))
        .filter(|v| (1..=8).contains(v))
}

/// The image as displayed: OpenCV's transforms for values 2-8 (2 mirror, 3 rotate 180,
/// 4 flip, 5 transpose, 6 rotate 90 clockwise, 7 transverse, 8 rotate 90 counter-clockwise).
pub(crate) fn apply(img: RgbImage, orientation: u16) -> RgbImage {
    use image::imageops::{flip_horizontal, flip_vertical, rotate90, rotate180, rotate270};
    match orientation {
        2 => flip_horizontal(&img),
        3 => rotate180(&img),
        4 => flip_vertical(&img),
        5 => flip_horizontal(&rotate90(&img)),
        6 => rotate90(&img),
        7 => flip_horizontal(&rotate270(&img)),
        8 => rotate270(&img),
        _ => img,
    }
}

/// Width and height once `orientation` is applied.
pub(crate) fn oriented_size((w, h): (u32, u32), orientation: u16) -> (u32, u32) {
    if orientation >= 5 { (h, w) } else { (w, h) }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 2x1 image (red, green) through each orientation, pixel by pixel as OpenCV maps them.
    #[test]
    fn the_eight_orientations_map_pixels_as_opencv_does() {
        let img = RgbImage::from_fn(3, 2, |x, y| image::Rgb([x as u8, y as u8, 0]));
        let at = |o: u16, x: u32, y: u32| {
            let p = apply(img.clone(), o);
            let q = p.get_pixel(x, y);
            (q[0], q[1])
        };
        // (x, y) of the stored image found at the displayed (0, 0) and the displayed size.
        assert_eq!(
            (at(1, 0, 0), apply(img.clone(), 1).dimensions()),
            ((0, 0), (3, 2))
        );
        assert_eq!(at(2, 0, 0), (2, 0));
        assert_eq!(at(3, 0, 0), (2, 1));
        assert_eq!(at(4, 0, 0), (0, 1));
        assert_eq!((at(5, 0, 0), at(5, 1, 0)), ((0, 0), (0, 1)));
        assert_eq!((at(6, 0, 0), at(6, 1, 0)), ((0, 1), (0, 0)));
        assert_eq!((at(7, 0, 0), at(7, 1, 0)), ((2, 1), (2, 0)));
        assert_eq!((at(8, 0, 0), at(8, 1, 0)), ((2, 0), (2, 1)));
        assert_eq!(apply(img, 6).dimensions(), (2, 3));
    }

    #[test]
    fn no_exif_or_a_broken_one_is_1() {
        assert_eq!(exif_orientation(b"\xff\xd8\xff\xd9"), 1);
        assert_eq!(
            exif_orientation(b"\xff\xd8\xff\xe1\x00\x08Exif\x00\x00\xff\xd9"),
            1
        );
        assert_eq!(exif_orientation(b""), 1);
    }
}
