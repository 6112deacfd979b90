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
        let (s, ok) = self.sample_at(wo);
        ok.then_some(s)
    }

    /// [`sample`](Self::sample) without a branch (for the lane kernels' loops): the sample
    /// and whether there is one.
    #[inline(always)]
    pub fn sample_at(&self, wo: Vec3) -> (BsdfSample, bool) {
        (BsdfSample { wi: reflect(wo), weight: self.reflectance, pdf: 1.0, delta: true }, wo.z > 0.0)
    }
}

/// `wo` reflected about +Z.
#[inline]
pub fn reflect(wo: Vec3) -> Vec3 {
    Vec3::new(-wo.x, -wo.y, wo.z)
}
