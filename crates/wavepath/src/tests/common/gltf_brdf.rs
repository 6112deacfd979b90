//! glTF's BRDF in f64, written from the specification's appendix B (and the
//! specular-glossiness extension's reference) in its own terms: the GGX distribution, the
//! height-correlated visibility V = G / (4 |n.l| |n.v|) in closed form, Schlick's Fresnel,
//! and the mix of the dielectric and metal BRDFs by metalness. Independent of the renderer's
//! formulation (Smith Lambda, one Fresnel colour).

use glam::DVec3;
use std::f64::consts::PI;

/// A glTF surface: metallic-roughness, or specular-glossiness.
#[derive(Clone, Copy, Debug)]
pub enum Surface {
    MetalRough { base: DVec3, metallic: f64, roughness: f64 },
    SpecGloss { diffuse: DVec3, specular: DVec3, glossiness: f64 },
}

fn schlick(f0: DVec3, v_dot_h: f64) -> DVec3 {
    f0 + (DVec3::ONE - f0) * (1.0 - v_dot_h.abs()).powi(5)
}

/// D(h) V(l, v): the specular BRDF without Fresnel.
fn specular(alpha: f64, n_l: f64, n_v: f64, n_h: f64) -> f64 {
    let a2 = alpha * alpha;
    let t = n_h * n_h * (a2 - 1.0) + 1.0;
    let d = a2 / (PI * t * t);
    let gv = n_l * (n_v * n_v * (1.0 - a2) + a2).sqrt();
    let gl = n_v * (n_l * n_l * (1.0 - a2) + a2).sqrt();
    d * 0.5 / (gv + gl)
}

/// f(v, l) in the local frame (normal +Z); zero below the surface.
pub fn brdf(s: Surface, v: DVec3, l: DVec3) -> DVec3 {
    if v.z <= 0.0 || l.z <= 0.0 {
        return DVec3::ZERO;
    }
    let h = (v + l).normalize();
    let v_h = v.dot(h);
    match s {
        Surface::MetalRough { base, metallic, roughness } => {
            let spec = specular((roughness * roughness).max(1e-4), l.z, v.z, h.z);
            let f_dielectric = schlick(DVec3::splat(0.04), v_h);
            let dielectric = (DVec3::ONE - f_dielectric) * base / PI + f_dielectric * spec;
            let metal = schlick(base, v_h) * spec;
            dielectric * (1.0 - metallic) + metal * metallic
        }
        Surface::SpecGloss { diffuse, specular: f0, glossiness } => {
            let r = 1.0 - glossiness;
            let spec = specular((r * r).max(1e-4), l.z, v.z, h.z);
            let f = schlick(f0, v_h);
            let c_diff = diffuse * (1.0 - f0.max_element());
            (DVec3::ONE - f) * c_diff / PI + f * spec
        }
    }
}

/// The directional albedo: f cos over the hemisphere of incident directions, by the
/// midpoint rule in (cos theta, phi) with `n` x `n` cells (phi over half the circle,
/// counted twice: `v` lies in the x-z plane, so the integrand is symmetric).
pub fn albedo(s: Surface, v: DVec3, n: usize) -> DVec3 {
    let mut sum = DVec3::ZERO;
    for i in 0..n {
        let c = (i as f64 + 0.5) / n as f64;
        let st = (1.0 - c * c).sqrt();
        for j in 0..n {
            let p = (j as f64 + 0.5) / n as f64 * PI;
            let l = DVec3::new(st * p.cos(), st * p.sin(), c);
            sum += brdf(s, v, l) * c;
        }
    }
    sum * (2.0 * PI / (n * n) as f64)
}
