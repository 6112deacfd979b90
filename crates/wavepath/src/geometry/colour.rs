//! Colour weights shared by the film (adaptive sampling) and the lights (environment-map
//! importance).

use glam::Vec3;

/// Luminance weights the reference uses for adaptive sampling (`illum()`).
#[inline]
pub fn illuminance(c: Vec3) -> f32 {
    0.2126 * c.x + 0.7152 * c.y + 0.0722 * c.z
}
