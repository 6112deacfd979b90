use super::Film;
use glam::Vec3;

/// The reference renderer's sample-rate colouring: r = samples / maximum through the ramp
/// blue (r = 0) -> green (r = 1/2) -> red (r = 1), linear between.
pub fn rate_color(rate: f32) -> Vec3 {
    let r = rate.clamp(0.0, 1.0);
    if r <= 0.5 {
        let t = (0.5 - r) / 0.5;
        Vec3::Z * t + Vec3::Y * (1.0 - t)
    } else {
        let t = (1.0 - r) / 0.5;
        Vec3::Y * t + Vec3::X * (1.0 - t)
    }
}

/// The sample-rate image: each pixel coloured by samples taken / `max_samples`. Values are
/// display values (write with a linear transfer, or see `write_rate_image`).
pub fn rate_film(width: usize, height: usize, samples: &[u32], max_samples: u32) -> Film {
    let m = max_samples.max(1) as f32;
    Film { width, height, pixels: samples.iter().map(|&s| rate_color(s as f32 / m)).collect() }
}

/// Writes the rate image as an 8-bit PNG with the colours as they are (no tone mapping).
pub fn write_rate_image(film: &Film, path: &std::path::Path) -> anyhow::Result<()> {
    let mut data = Vec::with_capacity(film.pixels.len() * 3);
    for y in (0..film.height).rev() {
        for x in 0..film.width {
            let c = film.get(x, y);
            data.extend([c.x, c.y, c.z].map(|v| (v.clamp(0.0, 1.0) * 255.0 + 0.5) as u8));
        }
    }
    let img = image::RgbImage::from_raw(film.width as u32, film.height as u32, data)
        .ok_or_else(|| anyhow::anyhow!("{}: image size mismatch", path.display()))?;
    img.save_with_format(path, image::ImageFormat::Png)
        .map_err(|e| anyhow::anyhow!("{}: cannot write image: {e}", path.display()))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ramp_ends_and_middle() {
        assert_eq!(rate_color(0.0), Vec3::Z);
        assert_eq!(rate_color(0.5), Vec3::Y);
        assert_eq!(rate_color(1.0), Vec3::X);
        assert_eq!(rate_color(0.75), Vec3::new(0.5, 0.5, 0.0));
    }
}
