//! Light sampling: every light of a scene as something a shading point can draw a
//! direction toward, with the radiance that arrives and its density.
//!
//! Semantics follow the CS184 reference renderer (every course rule: [`crate::cs184`]):
//! - point and spot lights have no distance falloff (the reference ignores COLLADA
//!   attenuation and divides by nothing); a directional light is a radiance along a direction;
//! - an area light is one-sided, emitting toward `direction`;
//! - the hemisphere (ambient) light gives constant radiance from directions with y > 0;
//!   it is sampled cosine-weighted about the shading normal;
//! - emissive triangles become one light sampled by power, unless the scene has an area light
//!   (the CS184 Cornell boxes pair an area light with an emissive quad that only the camera
//!   and hemisphere-sampling rays see; sampling both would count that light twice).

pub mod emission;
mod emissive;
mod infinite;

pub use emissive::{EmissiveTriangles, Emitter};
pub use infinite::{Infinite, Sky, SkySample};

use crate::geometry::error_bound::gamma;
use crate::scene::{Environment, Light, Scene};
use glam::Vec3;

/// One light as the integrators sample it.
#[derive(Clone, Debug)]
pub enum SampledLight {
    Point {
        position: Vec3,
        intensity: Vec3,
    },
    Directional {
        to_light: Vec3,
        radiance: Vec3,
    },
    /// `cos_cutoff`: cosine of the cone's half-angle.
    Spot {
        position: Vec3,
        axis: Vec3,
        cos_cutoff: f32,
        exponent: f32,
        intensity: Vec3,
    },
    /// `cs184_pdf`: use the course renderer's pdf, `dist / (area cos)` instead of
    /// `dist^2 / (area cos)`. Its skeleton takes the light-side cosine from the unnormalised
    /// vector to the light point, so every light-sampled estimate it makes is the correct
    /// one times that distance; kept only to compare with renderers built on it
    /// ([`crate::cs184::area_pdf_distance`]).
    Area {
        position: Vec3,
        normal: Vec3,
        dim_x: Vec3,
        dim_y: Vec3,
        area: f32,
        radiance: Vec3,
        cs184_pdf: bool,
    },
    /// Light from infinity (hemisphere light, constant environment, environment map).
    Infinite(Infinite),
    Emissive(EmissiveTriangles),
}

/// A direction toward a light and what arrives along it.
#[derive(Clone, Copy, Debug)]
pub struct LightSample {
    /// Unit direction from the shading point toward the light.
    pub wi: Vec3,
    /// The point on the light (for finite lights); the shadow ray stops short of it.
    pub target: Option<Vec3>,
    /// Arriving radiance divided by the density of `wi` (solid angle), or the delta light's
    /// radiance for delta lights.
    pub weight: Vec3,
}

impl SampledLight {
    /// Whether [`sample`](Self::sample) reads its third number (only emissive triangles do:
    /// they pick a triangle with it); the others take two.
    #[inline]
    pub fn uses_third_number(&self) -> bool {
        matches!(self, SampledLight::Emissive(_))
    }

    pub fn is_delta(&self) -> bool {
        matches!(self, SampledLight::Point { .. } | SampledLight::Directional { .. } | SampledLight::Spot { .. })
    }

    /// Draws one sample toward the light from `p` with shading normal `n` (which the
    /// cosine-sampled infinite lights use); `u` are three uniform numbers.
    #[inline]
    pub fn sample(&self, p: Vec3, n: Vec3, u: [f32; 3]) -> Option<LightSample> {
        match *self {
            SampledLight::Point { position, intensity } => {
                let wi = (position - p).try_normalize()?;
                Some(LightSample { wi, target: Some(position), weight: intensity })
            }
            SampledLight::Directional { to_light, radiance } => {
                Some(LightSample { wi: to_light, target: None, weight: radiance })
            }
            SampledLight::Spot { position, axis, cos_cutoff, exponent, intensity } => {
                let wi = (position - p).try_normalize()?;
                let c = (-wi).dot(axis);
                if c < cos_cutoff {
                    return None;
                }
                let falloff = if exponent > 0.0 { c.max(0.0).powf(exponent) } else { 1.0 };
                Some(LightSample { wi, target: Some(position), weight: intensity * falloff })
            }
            SampledLight::Area { position, normal, dim_x, dim_y, area, radiance, cs184_pdf } => {
                let q = position + (u[0] - 0.5) * dim_x + (u[1] - 0.5) * dim_y;
                // One-sided: the light emits toward `normal`, so it must face the point.
                let (wi, inv_pdf) = area_to_solid_angle(p, q, normal, area, true)?;
                let bias = if cs184_pdf { crate::cs184::area_light_pdf_weight((q - p).length()) } else { 1.0 };
                Some(LightSample { wi, target: Some(q), weight: radiance * (inv_pdf * bias) })
            }
            SampledLight::Infinite(ref inf) => inf.sample(n, [u[0], u[1]]),
            SampledLight::Emissive(ref e) => e.sample(p, u),
        }
    }
}

impl SampledLight {
    /// Per-component bound on the rounding error of any light point [`sample`](Self::sample)
    /// returns (its `target`): a shadow ray toward it stops short by this much, so the
    /// surface the point was sampled on never occludes it. Point and spot positions are
    /// given, not computed, and have none.
    #[inline]
    pub fn point_error(&self) -> Vec3 {
        match *self {
            // position + s dim_x + t dim_y with |s|, |t| <= 1/2: two products and two sums.
            SampledLight::Area { position, dim_x, dim_y, .. } => {
                gamma(3) * (position.abs() + 0.5 * (dim_x.abs() + dim_y.abs()))
            }
            SampledLight::Emissive(ref e) => e.point_error(),
            _ => Vec3::ZERO,
        }
    }
}

/// What a ray from a shading point found, for asking a light how likely its light sampling
/// was to pick the ray's direction ([`SampledLight::radiance_pdf`]).
#[derive(Clone, Copy, Debug)]
pub enum Seen {
    /// The ray left the scene.
    Miss,
    /// The ray's closest hit at distance `t`; `emitter`: the hit is an emissive triangle,
    /// with its emission, geometric normal and index in the mesh.
    Hit { t: f32, emitter: Option<(Vec3, Vec3, u32)> },
}

impl SampledLight {
    /// [`sample`](Self::sample) plus the solid-angle density of the drawn direction
    /// (infinite for delta lights, which only light sampling can find).
    #[inline]
    pub fn sample_pdf(&self, p: Vec3, n: Vec3, u: [f32; 3]) -> Option<(LightSample, f32)> {
        match *self {
            SampledLight::Area { normal, area, cs184_pdf, .. } => {
                let ls = self.sample(p, n, u)?;
                let dist2 = (ls.target? - p).length_squared();
                let d = if cs184_pdf { crate::cs184::area_pdf_distance(dist2.sqrt()) } else { dist2 };
                Some((ls, d / (-ls.wi.dot(normal) * area)))
            }
            SampledLight::Infinite(ref inf) => inf.sample_pdf(n, [u[0], u[1]]),
            SampledLight::Emissive(ref e) => e.sample_pdf(p, u),
            _ => self.sample(p, n, u).map(|ls| (ls, f32::INFINITY)),
        }
    }

    /// The radiance this light sends back along a ray from `p` (shading normal `n`) in
    /// direction `wi` that found `seen`, and the solid-angle density with which
    /// [`sample`](Self::sample) draws `wi` from `p`; `None` when the ray does not reach the
    /// light (delta lights never are reached). An area light is reached when the ray meets
    /// its parallelogram from the front no farther than a shadow ray toward that point
    /// would be unoccluded.
    #[inline]
    pub fn radiance_pdf(&self, p: Vec3, n: Vec3, wi: Vec3, seen: Seen) -> Option<(Vec3, f32)> {
        match *self {
            SampledLight::Area { position, normal, dim_x, dim_y, area, radiance, cs184_pdf } => {
                let cos_l = -wi.dot(normal);
                if cos_l <= 0.0 {
                    return None;
                }
                let t = (position - p).dot(normal) / -cos_l;
                if !(t > 0.0 && t.is_finite()) {
                    return None;
                }
                let q = p + t * wi;
                let d = q - position;
                if d.dot(dim_x).abs() > 0.5 * dim_x.length_squared()
                    || d.dot(dim_y).abs() > 0.5 * dim_y.length_squared()
                {
                    return None;
                }
                if let Seen::Hit { t: th, .. } = seen
                    && th < crate::geometry::offset::shadow_tmax(p, q, self.point_error())
                {
                    return None;
                }
                let pdf = if cs184_pdf { crate::cs184::area_pdf_distance(t) } else { t * t } / (cos_l * area);
                pdf.is_finite().then_some((radiance, pdf))
            }
            SampledLight::Infinite(ref inf) => match seen {
                Seen::Miss => Some(inf.radiance_pdf(n, wi)),
                Seen::Hit { .. } => None,
            },
            SampledLight::Emissive(ref e) => match seen {
                Seen::Hit { t, emitter: Some((emission, ng, prim)) } => {
                    let cos = wi.dot(ng).abs();
                    let pdf = t * t * e.area_density(prim) / cos;
                    (cos > 0.0 && pdf.is_finite()).then_some((emission, pdf))
                }
                _ => None,
            },
            _ => None,
        }
    }
}

/// Turns a point `q` drawn uniformly on a light of area `area` with normal `nl` into a
/// direction from `p`: the unit direction and 1 / its solid-angle density,
/// `area |cos_l| / dist^2`. `one_sided`: the light emits only toward `nl` (CS184 area
/// lights), so points behind it get nothing. `None` for coincident points or grazing angles.
#[inline]
pub fn area_to_solid_angle(p: Vec3, q: Vec3, nl: Vec3, area: f32, one_sided: bool) -> Option<(Vec3, f32)> {
    let (wi, inv_pdf, valid) = area_to_solid_angle_lanes(p, q, nl, area, one_sided);
    valid.then_some((wi, inv_pdf))
}

/// [`area_to_solid_angle`] without branches, for the lane kernel (the same operations, so
/// the same bits): the direction, the factor, and whether they are valid.
#[inline(always)]
pub fn area_to_solid_angle_lanes(p: Vec3, q: Vec3, nl: Vec3, area: f32, one_sided: bool) -> (Vec3, f32, bool) {
    let d = q - p;
    let dist2 = d.length_squared();
    let dist = dist2.sqrt();
    let wi = d / dist;
    let c = -wi.dot(nl);
    let cos_l = if one_sided { c } else { c.abs() };
    let valid = (dist > 0.0) & dist.is_finite() & (cos_l > 0.0);
    (wi, area * cos_l / dist2, valid)
}

/// All lights of a scene plus what rays that leave the scene see.
#[derive(Clone, Debug, Default)]
pub struct LightSet {
    pub lights: Vec<SampledLight>,
    /// Radiance arriving from infinity (hemisphere light and constant environment): what a
    /// hemisphere-sampling ray that escapes the scene counts.
    pub infinite: Infinite,
    /// What a camera ray that misses everything sees, besides the map: the constant
    /// environment only (the reference shows the ambient light's sky as black).
    pub background: Vec3,
}

impl LightSet {
    pub fn new(scene: &Scene) -> LightSet {
        let mut lights = Vec::new();
        let mut infinite = Infinite::default();
        for l in &scene.lights {
            match *l {
                Light::Point { position, intensity, .. } => lights.push(SampledLight::Point { position, intensity }),
                Light::Directional { direction, radiance } => {
                    if let Some(d) = direction.try_normalize() {
                        lights.push(SampledLight::Directional { to_light: -d, radiance });
                    }
                }
                Light::Spot { position, direction, intensity, cone_angle, falloff_exponent } => {
                    if let Some(axis) = direction.try_normalize() {
                        // `cone_angle` is the full cone angle (COLLADA falloff_angle) in degrees.
                        let cos_cutoff = (0.5 * cone_angle).to_radians().clamp(0.0, std::f32::consts::PI).cos();
                        lights.push(SampledLight::Spot {
                            position,
                            axis,
                            cos_cutoff,
                            exponent: falloff_exponent.max(0.0),
                            intensity,
                        });
                    }
                }
                Light::Hemisphere { radiance } => infinite.upper += radiance,
                Light::Area { position, direction, dim_x, dim_y, radiance } => {
                    let area = dim_x.length() * dim_y.length();
                    if let Some(normal) = direction.try_normalize()
                        && area > 0.0
                    {
                        lights.push(SampledLight::Area {
                            position,
                            normal,
                            dim_x,
                            dim_y,
                            area,
                            radiance,
                            cs184_pdf: false,
                        });
                    }
                }
            }
        }
        let mut background = Vec3::ZERO;
        match &scene.env {
            Environment::Constant(c) => {
                infinite.all += *c;
                background = *c;
            }
            Environment::Map(m) => infinite.map = Some(m.clone()),
            Environment::None => {}
        }
        if infinite.upper != Vec3::ZERO || infinite.all != Vec3::ZERO || infinite.map.is_some() {
            lights.push(SampledLight::Infinite(infinite.clone()));
        }
        let has_area = scene.lights.iter().any(|l| matches!(l, Light::Area { .. }));
        if !has_area && let Some(e) = EmissiveTriangles::new(scene) {
            lights.push(SampledLight::Emissive(e));
        }
        LightSet { lights, infinite, background }
    }

    /// Switches every area light to the CS184 course renderer's biased pdf.
    pub fn use_cs184_area_pdf(&mut self) {
        for l in &mut self.lights {
            if let SampledLight::Area { cs184_pdf, .. } = l {
                *cs184_pdf = true;
            }
        }
    }

    /// What a camera ray that misses everything sees looking toward `dir` (unit).
    #[inline]
    pub fn background_toward(&self, dir: Vec3) -> Vec3 {
        let mapped = self.infinite.map.as_ref().map_or(Vec3::ZERO, |m| m.radiance(dir));
        LightSet::background_with(self.background, mapped, self.infinite.map.is_some())
    }

    /// [`background_toward`](Self::background_toward) for the set's `background` with the
    /// map's radiance looked up by the caller (`mapped`, read only when `has_map`), as
    /// [`Sky::radiance_with`].
    #[inline(always)]
    pub fn background_with(background: Vec3, mapped: Vec3, has_map: bool) -> Vec3 {
        if has_map { background + mapped } else { background }
    }

    /// Samples taken for light `i` at one shading point: one for delta lights, `-l` otherwise.
    #[inline]
    pub fn samples_for(&self, i: usize, light_samples: u32) -> u32 {
        if self.lights[i].is_delta() { 1 } else { light_samples.max(1) }
    }

    /// Shadow rays one shading point casts at most (light sampling).
    pub fn samples_per_point(&self, light_samples: u32) -> u32 {
        (0..self.lights.len()).map(|i| self.samples_for(i, light_samples)).sum()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::Sampler;

    /// Irradiance from a small square area light directly above a point: E ~ L A / d^2.
    #[test]
    fn area_light_estimates_irradiance() {
        let light = SampledLight::Area {
            position: Vec3::new(0.0, 2.0, 0.0),
            normal: -Vec3::Y,
            dim_x: Vec3::X * 0.02,
            dim_y: Vec3::Z * 0.02,
            area: 0.0004,
            radiance: Vec3::splat(5.0),
            cs184_pdf: false,
        };
        let mut s = Sampler::for_sample(1, 0, 0);
        let mut e = 0.0f64;
        let n = 1000;
        for _ in 0..n {
            let ls = light.sample(Vec3::ZERO, Vec3::Y, [s.next_f32(), s.next_f32(), s.next_f32()]).unwrap();
            e += (ls.weight.x * ls.wi.y) as f64;
        }
        let expect = 5.0 * 0.0004 / 4.0;
        assert!((e / n as f64 - expect).abs() < expect * 1e-3, "{} vs {expect}", e / n as f64);
        // From above the light (its back side) nothing arrives.
        assert!(light.sample(Vec3::new(0.0, 3.0, 0.0), -Vec3::Y, [0.5; 3]).is_none());
    }

    /// A constant environment sampled cosine-weighted gives E = pi L with zero variance.
    #[test]
    fn constant_environment_irradiance() {
        let light = SampledLight::Infinite(Infinite { upper: Vec3::ZERO, all: Vec3::splat(2.0), map: None });
        let n = Vec3::new(0.3, 0.4, -0.5).normalize();
        let mut s = Sampler::for_sample(2, 0, 0);
        for _ in 0..100 {
            let ls = light.sample(Vec3::ZERO, n, [s.next_f32(), s.next_f32(), 0.0]).unwrap();
            let e = ls.weight.x * ls.wi.dot(n);
            assert!((e - 2.0 * std::f32::consts::PI).abs() < 1e-3);
        }
    }
}
