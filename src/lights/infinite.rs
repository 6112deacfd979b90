use glam::Vec3;

/// Radiance arriving from infinity: `upper` from directions with y > 0 (the CS184 hemisphere
/// light), `all` from every direction (a constant environment).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Infinite {
    pub upper: Vec3,
    pub all: Vec3,
}

impl Infinite {
    /// Radiance arriving along `-wi` (looking toward `wi`).
    #[inline]
    pub fn radiance(&self, wi: Vec3) -> Vec3 {
        if wi.y > 0.0 { self.upper + self.all } else { self.all }
    }
}
