use super::BsdfSample;
use glam::Vec3;

/// Perfect specular reflection about the shading normal, tinted by `reflectance` (the
/// CS184 mirror: no Fresnel).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Mirror {
    pub reflectance: Vec3,
}

impl Mirror {
    #[inline]
    pub fn sample(&self, wo: Vec3) -> Option<BsdfSample> {
        if wo.z <= 0.0 {
            return None;
        }
        Some(BsdfSample { wi: reflect(wo), weight: self.reflectance, pdf: 1.0, delta: true })
    }
}

/// `wo` reflected about +Z.
#[inline]
pub fn reflect(wo: Vec3) -> Vec3 {
    Vec3::new(-wo.x, -wo.y, wo.z)
}
