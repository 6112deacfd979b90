//! Lights as the start of light paths (bidirectional transport): a point and a direction
//! drawn from what a light emits, with the densities multiple importance sampling weighs
//! them by, and the same densities for a light point reached from the camera's side.
//!
//! The CS184 rule that point and spot lights have no distance falloff (see the module
//! above) has no physical emitter behind it; a light path from such a light carries the
//! squared length of its first segment as a factor ([`Emission::falloff_free`]), which is
//! what makes its estimate the path tracer's, `I cos / 1`, rather than `I cos / d^2`.

use super::SampledLight;
use crate::geometry::illuminance;
use crate::sampling::{Frame, warp};
use glam::Vec3;
use std::f32::consts::{FRAC_1_PI, PI};

/// A light path's first vertex and direction.
#[derive(Clone, Copy, Debug)]
pub struct Emission {
    pub pos: Vec3,
    /// Rounding error bound of `pos`.
    pub pos_error: Vec3,
    /// The emitting surface's normal (zero for point and spot lights).
    pub normal: Vec3,
    pub dir: Vec3,
    /// Emitted radiance (intensity for point and spot lights, radiance for a directional
    /// one) times the cosine at the light, over the two densities: the path's throughput.
    pub weight: Vec3,
    /// Density of `pos` per unit area (1 for a point position, which no other strategy can
    /// draw).
    pub pdf_pos: f32,
    /// Solid-angle density of `dir` (1 for a directional light's single direction).
    pub pdf_dir: f32,
    /// |cos| between `dir` and `normal` (1 for lights without a surface).
    pub cos: f32,
    /// The position is a point no ray can hit (point and spot lights).
    pub delta_pos: bool,
    /// The direction is the only one (directional lights).
    pub delta_dir: bool,
    /// A CS184 point or spot light: the first segment's throughput is multiplied by its
    /// squared length.
    pub falloff_free: bool,
}

impl Emission {
    /// Whether a light path can start here: a finite, non-zero weight and both densities
    /// positive.
    #[inline]
    pub fn usable(&self) -> bool {
        self.weight.is_finite() && self.weight != Vec3::ZERO && self.pdf_pos > 0.0 && self.pdf_dir > 0.0
    }
}

/// A point on a light seen from a shading point (a light-sampled connection), with the
/// densities of both ways of drawing it.
#[derive(Clone, Copy, Debug)]
pub struct Illumination {
    /// Unit direction from the shading point toward the light.
    pub wi: Vec3,
    /// The light point (`None` for a directional light, infinitely far).
    pub target: Option<Vec3>,
    /// Radiance (or a delta light's intensity, falloff-free) arriving along `-wi`.
    pub radiance: Vec3,
    /// Solid-angle density of `wi` when drawn from the shading point (for a delta light, 1:
    /// the estimate is `radiance` itself, and no other strategy reaches it).
    pub direct_pdf_w: f32,
    /// Density per unit area of the light point when drawn from the shading point (the
    /// same point in area measure), 1 for delta positions.
    pub direct_pdf_a: f32,
    /// Density (area x solid angle) with which [`SampledLight::emit`] would start a light
    /// path at the point toward the shading point.
    pub emission_pdf_w: f32,
    /// |cos| at the light (1 for lights without a surface).
    pub cos_light: f32,
    pub delta: bool,
}

/// The scene's bounding sphere: where a directional light's paths start (a disk of its
/// radius facing the light, outside the scene).
#[derive(Clone, Copy, Debug)]
pub struct SceneSphere {
    pub center: Vec3,
    pub radius: f32,
}

impl SampledLight {
    /// The power of the light (illuminance units), which light paths and light samples
    /// choose lights in proportion to. A CS184 point light has none (it does not fall off),
    /// so its intensity over the sphere stands in.
    pub fn power(&self, sphere: &SceneSphere) -> f32 {
        let p = match self {
            SampledLight::Point { intensity, .. } => 4.0 * PI * illuminance(*intensity),
            SampledLight::Spot { intensity, cos_cutoff, .. } => 2.0 * PI * (1.0 - cos_cutoff) * illuminance(*intensity),
            SampledLight::Directional { radiance, .. } => PI * sphere.radius * sphere.radius * illuminance(*radiance),
            SampledLight::Area { area, radiance, .. } => PI * area * illuminance(*radiance),
            SampledLight::Emissive(e) => PI * e.total_power(),
            SampledLight::Infinite(_) => 0.0,
        };
        if p.is_finite() { p.max(0.0) } else { 0.0 }
    }

    /// Starts a light path: `u` are five uniform numbers (position, direction, and a choice
    /// of triangle and side for emissive triangles). `None` for a light that emits nothing
    /// toward the drawn direction or cannot start paths (light from infinity).
    pub fn emit(&self, u: [f32; 5], sphere: &SceneSphere) -> Option<Emission> {
        let e = match *self {
            SampledLight::Point { position, intensity } => {
                let dir = uniform_sphere(u[2], u[3]);
                let pdf_dir = 1.0 / (4.0 * PI);
                point_emission(position, dir, intensity / pdf_dir, pdf_dir)
            }
            SampledLight::Spot { position, axis, cos_cutoff, exponent, intensity } => {
                let cos = 1.0 - u[2] * (1.0 - cos_cutoff);
                let sin = (1.0 - cos * cos).max(0.0).sqrt();
                let phi = 2.0 * PI * u[3];
                let dir = Frame::new(axis).to_world(Vec3::new(sin * phi.cos(), sin * phi.sin(), cos));
                let pdf_dir = 1.0 / (2.0 * PI * (1.0 - cos_cutoff));
                let falloff = if exponent > 0.0 { cos.max(0.0).powf(exponent) } else { 1.0 };
                point_emission(position, dir, intensity * falloff / pdf_dir, pdf_dir)
            }
            SampledLight::Directional { to_light, radiance } => {
                let f = Frame::new(to_light);
                let d = warp::concentric_disk(u[0], u[1]) * sphere.radius;
                let pos = sphere.center + sphere.radius * to_light + f.t * d.x + f.b * d.y;
                let pdf_pos = 1.0 / (PI * sphere.radius * sphere.radius);
                Emission {
                    pos,
                    pos_error: Vec3::ZERO,
                    normal: -to_light,
                    dir: -to_light,
                    weight: radiance / pdf_pos,
                    pdf_pos,
                    pdf_dir: 1.0,
                    cos: 1.0,
                    delta_pos: false,
                    delta_dir: true,
                    falloff_free: false,
                }
            }
            SampledLight::Area { position, normal, dim_x, dim_y, area, radiance, .. } => {
                let pos = position + (u[0] - 0.5) * dim_x + (u[1] - 0.5) * dim_y;
                surface_emission(pos, self.point_error(), normal, radiance, 1.0 / area, [u[2], u[3]])?
            }
            SampledLight::Emissive(ref e) => {
                let i = e.pick(u[4])?;
                let tri = e.triangle(i);
                if !tri.valid {
                    return None;
                }
                let (pos, bu, bv) = tri.point(u[0], u[1]);
                let le = e.emitted(i, bu, bv);
                // A two-sided emitter's side from the first direction number, reused.
                let (n, a) = match tri.one_sided {
                    true => (tri.n, u[2]),
                    false if u[2] < 0.5 => (tri.n, 2.0 * u[2]),
                    false => (-tri.n, 2.0 * u[2] - 1.0),
                };
                let mut em = surface_emission(
                    pos,
                    e.point_error(),
                    n,
                    le,
                    1.0 / tri.inv_density,
                    [a.min(1.0 - f32::EPSILON), u[3]],
                )?;
                if !tri.one_sided {
                    em.pdf_dir *= 0.5;
                    em.weight *= 2.0;
                }
                em
            }
            SampledLight::Infinite(_) => return None,
        };
        e.usable().then_some(e)
    }

    /// A point on the light toward which a shading point at `p` connects: `u` as for
    /// [`sample`](Self::sample). `None` when the light sends nothing toward `p`.
    pub fn illuminate(&self, p: Vec3, u: [f32; 3], sphere: &SceneSphere) -> Option<Illumination> {
        let delta = |wi: Vec3, target: Option<Vec3>, radiance: Vec3, emission_pdf_w: f32| Illumination {
            wi,
            target,
            radiance,
            direct_pdf_w: 1.0,
            direct_pdf_a: 1.0,
            emission_pdf_w,
            cos_light: 1.0,
            delta: true,
        };
        let il = match *self {
            SampledLight::Point { position, intensity } => {
                let wi = (position - p).try_normalize()?;
                delta(wi, Some(position), intensity, 1.0 / (4.0 * PI))
            }
            SampledLight::Spot { cos_cutoff, .. } => {
                let ls = self.sample(p, Vec3::Z, u)?;
                delta(ls.wi, ls.target, ls.weight, 1.0 / (2.0 * PI * (1.0 - cos_cutoff)))
            }
            SampledLight::Directional { to_light, radiance } => {
                delta(to_light, None, radiance, 1.0 / (PI * sphere.radius * sphere.radius))
            }
            SampledLight::Area { position, normal, dim_x, dim_y, area, radiance, .. } => {
                let q = position + (u[0] - 0.5) * dim_x + (u[1] - 0.5) * dim_y;
                surface_illumination(p, q, normal, radiance, 1.0 / area, true)?
            }
            SampledLight::Emissive(ref e) => {
                let i = e.pick(u[2])?;
                let tri = e.triangle(i);
                if !tri.valid {
                    return None;
                }
                let (q, bu, bv) = tri.point(u[0], u[1]);
                let mut il =
                    surface_illumination(p, q, tri.n, e.emitted(i, bu, bv), 1.0 / tri.inv_density, tri.one_sided)?;
                if !tri.one_sided {
                    il.emission_pdf_w *= 0.5;
                }
                il
            }
            SampledLight::Infinite(_) => return None,
        };
        let ok = il.radiance.is_finite() && il.direct_pdf_w > 0.0 && il.direct_pdf_w.is_finite();
        ok.then_some(il)
    }
}

fn uniform_sphere(u: f32, v: f32) -> Vec3 {
    let z = 1.0 - 2.0 * u;
    let r = (1.0 - z * z).max(0.0).sqrt();
    let phi = 2.0 * PI * v;
    Vec3::new(r * phi.cos(), r * phi.sin(), z)
}

fn point_emission(pos: Vec3, dir: Vec3, weight: Vec3, pdf_dir: f32) -> Emission {
    Emission {
        pos,
        pos_error: Vec3::ZERO,
        normal: Vec3::ZERO,
        dir,
        weight,
        pdf_pos: 1.0,
        pdf_dir,
        cos: 1.0,
        delta_pos: true,
        delta_dir: false,
        falloff_free: true,
    }
}

/// A cosine-weighted direction about `n` from the point `pos` (density `pdf_pos` per area)
/// of a surface emitting `le`.
fn surface_emission(pos: Vec3, pos_error: Vec3, n: Vec3, le: Vec3, pdf_pos: f32, u: [f32; 2]) -> Option<Emission> {
    let local = warp::cosine_hemisphere(u[0], u[1]);
    if local.z <= 0.0 {
        return None;
    }
    let dir = Frame::new(n).to_world(local);
    let pdf_dir = local.z * FRAC_1_PI;
    Some(Emission {
        pos,
        pos_error,
        normal: n,
        dir,
        // Le cos / (pdf_pos cos / pi)
        weight: le * (PI / pdf_pos),
        pdf_pos,
        pdf_dir,
        cos: local.z,
        delta_pos: false,
        delta_dir: false,
        falloff_free: false,
    })
}

/// The light point `q` (normal `n`, density `pdf_a` per area) seen from `p`.
fn surface_illumination(p: Vec3, q: Vec3, n: Vec3, le: Vec3, pdf_a: f32, one_sided: bool) -> Option<Illumination> {
    let d = q - p;
    let dist2 = d.length_squared();
    let wi = d / dist2.sqrt();
    let c = -wi.dot(n);
    let cos_light = if one_sided { c } else { c.abs() };
    if !(cos_light > 0.0 && dist2 > 0.0 && dist2.is_finite()) {
        return None;
    }
    let direct_pdf_w = pdf_a * dist2 / cos_light;
    Some(Illumination {
        wi,
        target: Some(q),
        radiance: le,
        direct_pdf_w,
        direct_pdf_a: pdf_a,
        emission_pdf_w: pdf_a * cos_light * FRAC_1_PI,
        cos_light,
        delta: false,
    })
}
