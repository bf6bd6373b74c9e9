use image::GrayImage;

use crate::Resize;

/// An edge map (white edges on black) at the size the detector worked on.
///
/// `resize` maps frame coordinates to edge-map coordinates and back, so a
/// consumer working at the detector's size can return to frame pixels exactly.
#[derive(Debug, Clone, PartialEq)]
pub struct EdgeMap {
    pub index: usize,
    pub image: GrayImage,
    pub resize: Resize,
}
