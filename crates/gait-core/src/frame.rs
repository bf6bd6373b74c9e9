use image::RgbImage;

/// One RGB video frame (or image) with its index in the input.
#[derive(Debug, Clone, PartialEq)]
pub struct Frame {
    /// Zero-based position in the input sequence.
    pub index: usize,
    pub image: RgbImage,
}

impl Frame {
    pub fn new(index: usize, image: RgbImage) -> Self {
        Self { index, image }
    }

    pub fn width(&self) -> u32 {
        self.image.width()
    }

    pub fn height(&self) -> u32 {
        self.image.height()
    }
}

/// Sorted frame indices as inclusive `[first, last]` ranges (how run.json
/// lists frames).
pub fn ranges(frames: impl IntoIterator<Item = usize>) -> Vec<[usize; 2]> {
    let mut out: Vec<[usize; 2]> = Vec::new();
    for f in frames {
        match out.last_mut() {
            Some(r) if r[1] + 1 == f => r[1] = f,
            _ => out.push([f, f]),
        }
    }
    out
}
