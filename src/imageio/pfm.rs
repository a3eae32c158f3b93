//! PFM output: `PF`, `width height`, scale `-1` (little-endian, values as they are), then rows
//! of RGB `f32` from the bottom up, as pbrt-v4 writes `-o x.pfm`. [`super::decode::read_pfm`]
//! reads it back.
use super::{write_atomically, ImageError, RgbImage};
use std::path::Path;

/// Writes `rgb` to `path` as a linear PFM (temporary file, then renamed over `path`).
/// Errors: an inconsistent or empty image, file-system failures.
pub fn write_pfm(path: &Path, rgb: &RgbImage) -> Result<(), ImageError> {
    if !rgb.is_consistent() || rgb.width == 0 || rgb.height == 0 {
        return Err(ImageError::invalid(
            path,
            format!(
                "cannot write a {}x{} image holding {} pixels",
                rgb.width,
                rgb.height,
                rgb.pixels.len()
            ),
        ));
    }
    let mut bytes = format!("PF\n{} {}\n-1\n", rgb.width, rgb.height).into_bytes();
    bytes.reserve(rgb.pixels.len() * 12);
    for row in rgb.pixels.chunks(rgb.width).rev() {
        for v in row.iter().flatten() {
            bytes.extend_from_slice(&v.to_le_bytes());
        }
    }
    write_atomically(path, |tmp| {
        std::fs::write(tmp, &bytes).map_err(|e| ImageError::io(path, e))
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Written and read back through the texture decoder: the same values, rows top-down.
    #[test]
    fn round_trip_through_read_pfm() {
        let mut img = RgbImage::new(3, 2);
        img.set(0, 0, [1.0, 2.0, 3.0]);
        img.set(2, 1, [-0.5, 1e-7, 65504.0]);
        let path = std::env::temp_dir().join(format!("photon-pfm-{}.pfm", std::process::id()));
        write_pfm(&path, &img).unwrap();
        let bytes = std::fs::read(&path).unwrap();
        std::fs::remove_file(&path).unwrap();
        assert!(bytes.starts_with(b"PF\n3 2\n-1\n"));
        let t = super::super::decode::read_pfm(&bytes).unwrap();
        assert_eq!((t.width, t.height), (3, 2));
        assert_eq!(t.texels[0].to_array(), [1.0, 2.0, 3.0]);
        assert_eq!(t.texels[5].to_array(), [-0.5, 1e-7, 65504.0]);
        assert!(write_pfm(&path, &RgbImage::new(0, 0)).is_err());
    }
}
