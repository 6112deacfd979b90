//! Reading the PFM files the binary writes (little endian, rows bottom to top).

use std::path::Path;

/// A PFM image: its size and its pixels, row 0 at the bottom (the film's order).
pub struct Pfm {
    pub width: usize,
    pub height: usize,
    pub pixels: Vec<[f32; 3]>,
}

impl Pfm {
    /// The pixel in column `x` of row `y` counted from the top (an 8-bit image's order).
    pub fn top_down(&self, x: usize, y: usize) -> [f32; 3] {
        self.pixels[(self.height - 1 - y) * self.width + x]
    }
}

/// Reads a colour PFM (`PF`), panicking on anything else (a short file, a big-endian scale,
/// a size that does not match the bytes).
pub fn read_pfm(path: &Path) -> Pfm {
    let bytes = std::fs::read(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let (mut lines, mut pos) = (0, 0);
    while lines < 3 {
        assert!(pos < bytes.len(), "{}: the header is cut short", path.display());
        if bytes[pos] == b'\n' {
            lines += 1;
        }
        pos += 1;
    }
    let header = String::from_utf8_lossy(&bytes[..pos]).into_owned();
    let mut it = header.split_whitespace();
    assert_eq!(it.next(), Some("PF"), "{}: not a colour PFM", path.display());
    let width: usize = it.next().unwrap().parse().unwrap();
    let height: usize = it.next().unwrap().parse().unwrap();
    let scale: f32 = it.next().unwrap().parse().unwrap();
    assert!(scale < 0.0, "{}: not little endian", path.display());
    let floats: Vec<f32> = bytes[pos..].chunks_exact(4).map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]])).collect();
    assert_eq!(floats.len(), width * height * 3, "{}: {width}x{height} does not match its bytes", path.display());
    Pfm { width, height, pixels: floats.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect() }
}
