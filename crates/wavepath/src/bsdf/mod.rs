//! Scattering models behind one interface, all in a local shading frame: +Z is the shading
//! normal turned toward the side the path arrived from (`wo.z > 0` for every model but a
//! refracting one seen from a grazing shading normal), X and Y from [`Frame`].
//!
//! Conventions (pbrt's): `eval` returns f (no cosine); `sample` returns f |cos wi| / pdf as
//! `weight`; delta lobes (mirror, smooth glass) have `eval = pdf = 0` and set `delta`, with
//! `pdf` in the sample holding the discrete probability of the lobe chosen. No function
//! returns NaN or Inf for any unit input (grazing or below-surface directions give zero or
//! `None`).

mod branch_free;
mod dielectric;
mod glossy;
mod lambert;
mod layered;
mod microfacet;
mod mirror;
mod pbr;

pub use dielectric::Dielectric;
#[cfg(test)]
pub use dielectric::fresnel_dielectric;
pub use glossy::Glossy;
pub use lambert::Lambert;
pub use layered::{Layered, SHEEN_TABLE, sheen_albedo_table};
pub use microfacet::{Distribution, Microfacet};
pub use mirror::Mirror;
pub use pbr::Pbr;

use crate::sampling::Frame;
use crate::scene::Bsdf;
use glam::Vec3;

/// One sampled direction and what it carries.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BsdfSample {
    /// Incident direction, local frame.
    pub wi: Vec3,
    /// f |cos wi| / pdf (the throughput factor).
    pub weight: Vec3,
    /// Solid-angle density of `wi` (for delta lobes: the probability of choosing the lobe).
    pub pdf: f32,
    pub delta: bool,
}

impl BsdfSample {
    /// A direction `wi` drawn from a continuous mixture of density `pdf`, carrying
    /// `f(wi) cos / pdf` (`f` evaluated only for a usable density); `None` when the density
    /// or the weight is not a finite positive number, so no lobe returns a NaN or infinite
    /// throughput.
    #[inline]
    pub fn continuous(wi: Vec3, pdf: f32, f: impl FnOnce() -> Vec3) -> Option<BsdfSample> {
        if !(pdf > 0.0 && pdf.is_finite()) {
            return None;
        }
        let weight = f() * (wi.z / pdf);
        weight.is_finite().then_some(BsdfSample { wi, weight, pdf, delta: false })
    }
}

/// A material's scattering model, ready to shade (the file's parameters turned into what
/// the formulas need, once per render).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Model {
    Lambert(Lambert),
    Mirror(Mirror),
    Dielectric(Dielectric),
    Microfacet(Microfacet),
    Pbr(Pbr),
    Glossy(Glossy),
    /// The glTF model with its extensions' layers ([`Layered`]).
    Layered(Layered),
}

/// How a model's light is best estimated: which integrator strategy it needs.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kind {
    /// Lambertian: light sampling only (the fast path).
    Diffuse,
    /// Glossy: light sampling and BSDF sampling combined by multiple importance sampling.
    Glossy,
    /// Delta lobes only: no light sampling, emission along the sampled ray counts.
    Delta,
}

impl Model {
    /// The model of material `m`: [`Model::new`] of its BSDF, or the layered glTF model
    /// when it has extension layers.
    pub fn of_material(m: &crate::scene::Material) -> Model {
        match (&m.layers, &m.bsdf) {
            (Some(l), Bsdf::MetallicRoughness { base, metallic, roughness }) => {
                Model::Layered(Layered::new(*base, *metallic, *roughness, l.transmission, l))
            }
            _ => Model::new(&m.bsdf),
        }
    }

    /// The model of a material as the file states it. Glass roughness is ignored, as the
    /// CS184 reference does.
    pub fn new(b: &Bsdf) -> Model {
        match *b {
            Bsdf::Diffuse { albedo } => Model::Lambert(Lambert { albedo }),
            Bsdf::Phong { diffuse, specular, shininess } => Model::Glossy(Glossy::phong(diffuse, specular, shininess)),
            Bsdf::Mirror { reflectance } => Model::Mirror(Mirror { reflectance }),
            Bsdf::Glass { reflectance, transmittance, ior, .. } => {
                Model::Dielectric(Dielectric { reflectance, transmittance, eta: ior, reflect: true })
            }
            Bsdf::Refraction { transmittance, ior, .. } => {
                Model::Dielectric(Dielectric { reflectance: Vec3::ZERO, transmittance, eta: ior, reflect: false })
            }
            Bsdf::Microfacet { alpha, eta, k } => {
                Model::Microfacet(Microfacet { alpha, eta, k, distribution: Distribution::Beckmann })
            }
            Bsdf::MetallicRoughness { base, metallic, roughness } => {
                Model::Pbr(Pbr::metallic_roughness(base, metallic, roughness))
            }
            Bsdf::SpecularGlossiness { diffuse, specular, glossiness } => {
                Model::Pbr(Pbr::specular_glossiness(diffuse, specular, glossiness))
            }
        }
    }

    pub fn kind(&self) -> Kind {
        match self {
            Model::Lambert(_) => Kind::Diffuse,
            Model::Mirror(_) | Model::Dielectric(_) => Kind::Delta,
            Model::Microfacet(_) | Model::Pbr(_) | Model::Glossy(_) | Model::Layered(_) => Kind::Glossy,
        }
    }

    /// The colour a denoiser's albedo image takes for this model (Open Image Denoise asks for
    /// values in [0, 1], not a strict albedo): the diffuse colour plus the specular
    /// reflectance at normal incidence, clamped; `None` for delta models, which the image sees
    /// through to the next surface.
    pub fn albedo_estimate(&self) -> Option<Vec3> {
        let a = match self {
            Model::Lambert(l) => l.albedo,
            Model::Mirror(_) | Model::Dielectric(_) => return None,
            Model::Microfacet(m) => Vec3::new(
                microfacet::fresnel_conductor(1.0, m.eta.x, m.k.x),
                microfacet::fresnel_conductor(1.0, m.eta.y, m.k.y),
                microfacet::fresnel_conductor(1.0, m.eta.z, m.k.z),
            ),
            Model::Pbr(p) => p.diffuse + p.f0,
            Model::Glossy(g) => g.diffuse + g.specular,
            Model::Layered(l) => l.diffuse + l.transmit + l.f0,
        };
        Some(if a.is_finite() { a.clamp(Vec3::ZERO, Vec3::ONE) } else { Vec3::ZERO })
    }

    /// This model at a hit on the `front` (outer) side or the back side: a dielectric's
    /// relative index of refraction (transmitted over incident side) flips inside.
    #[inline]
    pub fn oriented(self, front: bool) -> Model {
        match self {
            Model::Dielectric(d) if !front => Model::Dielectric(Dielectric { eta: 1.0 / d.eta, ..d }),
            Model::Layered(l) if !front => Model::Layered(l.inside()),
            m => m,
        }
    }

    #[inline]
    pub fn eval(&self, wo: Vec3, wi: Vec3) -> Vec3 {
        match self {
            Model::Lambert(m) => m.eval(wo, wi),
            Model::Mirror(_) | Model::Dielectric(_) => Vec3::ZERO,
            Model::Microfacet(m) => m.eval(wo, wi),
            Model::Pbr(m) => m.eval(wo, wi),
            Model::Glossy(m) => m.eval(wo, wi),
            Model::Layered(m) => layered_eval(m, wo, wi),
        }
    }

    /// `u`: three uniform numbers (the third chooses between lobes).
    #[inline]
    pub fn sample(&self, wo: Vec3, u: [f32; 3]) -> Option<BsdfSample> {
        match self {
            Model::Lambert(m) => m.sample(wo, [u[0], u[1]]),
            Model::Mirror(m) => m.sample(wo),
            Model::Dielectric(m) => m.sample(wo, u[2]),
            Model::Microfacet(m) => m.sample(wo, [u[0], u[1]]),
            Model::Pbr(m) => m.sample(wo, u),
            Model::Glossy(m) => m.sample(wo, u),
            Model::Layered(m) => layered_sample(m, wo, u),
        }
    }

    /// [`eval`](Self::eval) and [`pdf`](Self::pdf) of one direction (fused where a model
    /// shares work between them; the same values either way).
    #[inline]
    pub fn eval_pdf(&self, wo: Vec3, wi: Vec3) -> (Vec3, f32) {
        match self {
            Model::Pbr(m) => m.eval_pdf(wo, wi),
            Model::Glossy(m) => m.eval_pdf(wo, wi),
            Model::Layered(m) => layered_eval_pdf(m, wo, wi),
            m => (m.eval(wo, wi), m.pdf(wo, wi)),
        }
    }

    #[inline]
    pub fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        match self {
            Model::Lambert(m) => m.pdf(wo, wi),
            Model::Mirror(_) | Model::Dielectric(_) => 0.0,
            Model::Microfacet(m) => m.pdf(wo, wi),
            Model::Pbr(m) => m.pdf(wo, wi),
            Model::Glossy(m) => m.pdf(wo, wi),
            Model::Layered(m) => layered_pdf(m, wo, wi),
        }
    }
}

// The layered model's calls out of line, so that the other models' dispatch stays as
// small (and as inlined) as it was.
#[inline(never)]
fn layered_eval(m: &Layered, wo: Vec3, wi: Vec3) -> Vec3 {
    m.eval(wo, wi)
}

#[inline(never)]
fn layered_sample(m: &Layered, wo: Vec3, u: [f32; 3]) -> Option<BsdfSample> {
    m.sample(wo, u)
}

#[inline(never)]
fn layered_eval_pdf(m: &Layered, wo: Vec3, wi: Vec3) -> (Vec3, f32) {
    m.eval_pdf(wo, wi)
}

#[inline(never)]
fn layered_pdf(m: &Layered, wo: Vec3, wi: Vec3) -> f32 {
    m.pdf(wo, wi)
}

/// `v` in the frame's coordinates (the inverse of [`Frame::to_world`]).
#[inline]
pub fn to_local(f: &Frame, v: Vec3) -> Vec3 {
    Vec3::new(v.dot(f.t), v.dot(f.b), v.dot(f.n))
}

/// Power heuristic (beta = 2) weight of a strategy with density `a` against one with `b`
/// (each already multiplied by its sample count); 0 when both are 0. Without branches (the
/// lane kernels' loops call it).
#[inline(always)]
pub fn power_heuristic(a: f32, b: f32) -> f32 {
    let (a2, b2) = (a * a, b * b);
    let w = a2 / (a2 + b2);
    if a2 + b2 > 0.0 && (a2 + b2).is_finite() {
        w
    } else if a.is_infinite() {
        1.0
    } else {
        0.0
    }
}
