//! Still images (an image input, a folder of frames) decoded as OpenCV's
//! `cv2.imread(path, IMREAD_COLOR)` decodes them, so keypoints match those of
//! Python pipelines on the same files: JPEG through libjpeg-turbo with EXIF
//! orientation applied (`jpeg`, `orientation`); PNG, BMP and TIFF through the
//! `image` crate, which decodes those losslessly, as stored.

mod jpeg;
mod orientation;

use std::path::Path;

use image::RgbImage;

/// A decoded still.
pub struct Still {
    pub image: RgbImage,
    /// The EXIF orientation found (1-8; 1 when none, and for formats other than JPEG).
    pub orientation: u16,
    /// libjpeg's warning for a damaged but decodable JPEG (as OpenCV, it decodes).
    pub warning: Option<String>,
}

fn is_jpeg(data: &[u8]) -> bool {
    data.starts_with(&[0xFF, 0xD8, 0xFF])
}

/// Reads and decodes `path`; the error is one line saying what is wrong with the file.
pub fn read(path: &Path) -> Result<Still, String> {
    let data = std::fs::read(path).map_err(|e| format!("cannot read it ({e})"))?;
    decode(&data)
}

/// Decodes the bytes of a still (JPEG by its signature, else what the `image` crate recognises).
pub fn decode(data: &[u8]) -> Result<Still, String> {
    if is_jpeg(data) {
        let d = jpeg::decode(data).map_err(|e| format!("not a readable JPEG ({e})"))?;
        let img = RgbImage::from_raw(d.width, d.height, d.rgb)
            .ok_or_else(|| "not a readable JPEG (wrong buffer size)".to_string())?;
        let o = orientation::exif_orientation(data);
        return Ok(Still {
            image: orientation::apply(img, o),
            orientation: o,
            warning: d.warning,
        });
    }
    let img = image::load_from_memory(data).map_err(|e| format!("unreadable image ({e})"))?;
    Ok(Still {
        image: img.to_rgb8(),
        orientation: 1,
        warning: None,
    })
}

/// Width and height as decoded (EXIF orientation applied), and the orientation, from the
/// file's header (its first bytes: a folder of frames is checked without reading it whole).
pub fn dimensions(path: &Path) -> Result<((u32, u32), u16), String> {
    use std::io::Read;
    const HEAD: u64 = 256 * 1024;
    let mut head = Vec::new();
    std::fs::File::open(path)
        .and_then(|f| f.take(HEAD).read_to_end(&mut head))
        .map_err(|e| format!("cannot read it ({e})"))?;
    if is_jpeg(&head) {
        // A header longer than the first bytes (large ICC profiles): read it all.
        let size = match jpeg::dimensions(&head) {
            Ok(size) => size,
            Err(_) if head.len() as u64 == HEAD => {
                let all = std::fs::read(path).map_err(|e| format!("cannot read it ({e})"))?;
                head = all;
                jpeg::dimensions(&head).map_err(|e| format!("not a readable JPEG ({e})"))?
            }
            Err(e) => return Err(format!("not a readable JPEG ({e})")),
        };
        let o = orientation::exif_orientation(&head);
        return Ok((orientation::oriented_size(size, o), o));
    }
    let size = image::ImageReader::open(path)
        .and_then(|r| r.with_guessed_format())
        .map_err(|e| format!("unreadable image ({e})"))?
        .into_dimensions()
        .map_err(|e| format!("unreadable image ({e})"))?;
    Ok((size, 1))
}
