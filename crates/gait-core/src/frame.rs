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
