//! STUB: image I/O (EXR through OpenEXRCore, PNG through `image`).
/// A linear RGB float image, row-major from the top-left pixel.
#[derive(Clone, Debug, PartialEq)]
pub struct RgbImage {
    pub width: usize,
    pub height: usize,
    pub pixels: Vec<[f32; 3]>,
}

impl RgbImage {
    pub fn new(width: usize, height: usize) -> Self {
        RgbImage {
            width,
            height,
            pixels: vec![[0.0; 3]; width * height],
        }
    }
}
