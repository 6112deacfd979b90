//! An equirectangular (lat-long) environment map: radiance by direction, and the
//! distribution that draws directions by luminance x sin(theta) (a 2D piecewise-constant
//! distribution over its texels; the light built on it lives in `lights`).
//!
//! Orientation follows the CS184 reference (`EnvironmentLight::dir_to_theta_phi`):
//! theta = acos(y) is measured from world +Y (row 0, the top of the image, is straight up),
//! phi = atan2(-z, x) + pi, and texel column u = phi / 2pi, row v = theta / pi. So the left
//! edge (u = 0) looks toward -X, u = 1/4 toward +Z, u = 1/2 toward +X, u = 3/4 toward -Z.
//!
//! Radiance is the texel the direction falls in (no filtering): the distribution's cells
//! are the texels, so the sampling density is exactly proportional to luminance x sin(theta)
//! of what [`EnvMap::radiance`] returns, and no texel with light has zero density.

use crate::geometry::trig;
use crate::sampling::distribution::Distribution2D;
use anyhow::{Result, anyhow, bail};
use glam::Vec3;
use std::f32::consts::{PI, TAU};
use std::path::{Path, PathBuf};

/// A loaded environment map with its sampling distribution.
#[derive(Clone)]
pub struct EnvMap {
    pub path: PathBuf,
    pub width: usize,
    pub height: usize,
    /// Row-major, row 0 at the top (+Y): each texel's radiance beside its sampling density,
    /// so that looking a direction up for both (an escaped ray, a MIS weight) reads one
    /// 16-byte entry.
    texels: Vec<Texel>,
    /// Sampling by luminance x sin(theta); its cells are the texels.
    dist: Distribution2D,
}

/// One texel: linear RGB and the density of [`Distribution2D`] in its cell (with respect to
/// du dv: the row's marginal times the column's conditional).
#[derive(Clone, Copy, Debug, PartialEq)]
struct Texel {
    rgb: Vec3,
    pdf_uv: f32,
}

impl std::fmt::Debug for EnvMap {
    // The texels are megabytes; the path and size identify the map (scene hashes use Debug).
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "EnvMap({}, {}x{})", self.path.display(), self.width, self.height)
    }
}

impl PartialEq for EnvMap {
    fn eq(&self, o: &Self) -> bool {
        self.path == o.path && self.width == o.width && self.height == o.height && self.texels == o.texels
    }
}

impl EnvMap {
    /// Reads an EXR or Radiance HDR (or any format the `image` crate reads) as linear RGB.
    pub fn load(path: &Path) -> Result<EnvMap> {
        let shown = path.display();
        let img = image::ImageReader::open(path)
            .map_err(|e| anyhow!("{shown}: cannot read environment map: {e}"))?
            .with_guessed_format()
            .map_err(|e| anyhow!("{shown}: cannot read environment map: {e}"))?
            .decode()
            .map_err(|e| anyhow!("{shown}: not a readable environment map: {e}"))?
            .into_rgb32f();
        let (w, h) = (img.width() as usize, img.height() as usize);
        let texels: Vec<Vec3> = img.pixels().map(|p| Vec3::from(p.0)).collect();
        EnvMap::from_texels(path.to_path_buf(), w, h, texels).map_err(|e| anyhow!("{shown}: {e}"))
    }

    /// A map from linear RGB texels (row 0 at the top); negative values count as zero.
    pub fn from_texels(path: PathBuf, width: usize, height: usize, mut texels: Vec<Vec3>) -> Result<EnvMap> {
        if width == 0 || height == 0 || texels.len() != width * height {
            bail!("environment map has no texels ({width}x{height})");
        }
        if let Some(i) = texels.iter().position(|t| !t.is_finite()) {
            bail!("environment map texel ({}, {}) is not finite", i % width, i / width);
        }
        for t in &mut texels {
            *t = t.max(Vec3::ZERO);
        }
        let weights: Vec<f32> = texels
            .iter()
            .enumerate()
            .map(|(i, t)| {
                let theta = ((i / width) as f32 + 0.5) / height as f32 * PI;
                crate::geometry::illuminance(*t) * theta.sin()
            })
            .collect();
        let dist = Distribution2D::new(&weights, width, height);
        let texels = texels
            .iter()
            .enumerate()
            .map(|(i, &rgb)| Texel { rgb, pdf_uv: dist.pdf_of_cell(i % width, i / width) })
            .collect();
        Ok(EnvMap { path, width, height, texels, dist })
    }

    /// Image coordinates (u, v) in [0,1] of direction `d` (unit).
    #[inline(always)]
    pub fn uv_of(d: Vec3) -> [f32; 2] {
        let theta = trig::acos(d.y);
        let phi = trig::atan2(-d.z, d.x) + PI;
        [phi / TAU, theta / PI]
    }

    /// The unit direction at image coordinates (u, v), and sin(theta) (the sphere's area
    /// element per du dv, over 2 pi^2).
    #[inline(always)]
    pub fn dir_sin_of(uv: [f32; 2]) -> (Vec3, f32) {
        let (st, ct) = trig::sin_cos_turns(uv[1] * 0.5);
        let (sp, cp) = trig::sin_cos_turns(uv[0]);
        (Vec3::new(-cp * st, ct, sp * st), st)
    }

    /// The unit direction at image coordinates (u, v).
    #[cfg(test)]
    pub fn dir_of(uv: [f32; 2]) -> Vec3 {
        Self::dir_sin_of(uv).0
    }

    /// The index of the texel direction `d` (unit) falls in, and the sine of its polar angle;
    /// plain arithmetic, so that a loop over lanes vectorises.
    #[inline(always)]
    pub fn index_of(&self, d: Vec3) -> (usize, f32) {
        let [u, v] = Self::uv_of(d);
        let x = ((u * self.width as f32) as usize).min(self.width - 1);
        let y = ((v * self.height as f32) as usize).min(self.height - 1);
        (y * self.width + x, ((1.0 - d.y) * (1.0 + d.y)).max(0.0).sqrt())
    }

    /// The texel (x, y) direction `d` falls in.
    #[inline]
    pub fn texel_of(&self, d: Vec3) -> (usize, usize) {
        let (i, _) = self.index_of(d);
        (i % self.width, i / self.width)
    }

    pub fn texel(&self, x: usize, y: usize) -> Vec3 {
        self.texels[y * self.width + x].rgb
    }

    /// Radiance arriving along `-d` (looking toward `d`, unit).
    #[inline]
    pub fn radiance(&self, d: Vec3) -> Vec3 {
        self.texels[self.index_of(d).0].rgb
    }

    /// The radiance and solid-angle density of texel `index` (from [`index_of`](Self::index_of)
    /// with `sin_theta`): one read; the density is zero at the poles.
    #[inline(always)]
    pub fn at_index(&self, index: usize, sin_theta: f32) -> (Vec3, f32) {
        let t = self.texels[index];
        (t.rgb, Self::solid_angle_pdf(t.pdf_uv, sin_theta))
    }

    /// Starts loading texel `index` (an escaped ray's, found well before it is read: a map's
    /// texels are megabytes and escaped rays point anywhere).
    #[inline(always)]
    pub fn prefetch(&self, index: usize) {
        if let Some(t) = self.texels.get(index) {
            crate::cpu::prefetch(t);
        }
    }

    /// Radiance toward `d` (unit) and the solid-angle density with which
    /// a light sample ([`draw`](Self::draw)) draws it.
    #[inline]
    pub fn lookup(&self, d: Vec3) -> (Vec3, f32) {
        let (i, st) = self.index_of(d);
        self.at_index(i, st)
    }

    /// A density per du dv as one per solid angle at a polar angle with sine `sin_theta`
    /// (zero where the sine is: the poles have no area).
    #[inline(always)]
    pub fn solid_angle_pdf(pdf_uv: f32, sin_theta: f32) -> f32 {
        if sin_theta > 0.0 { pdf_uv / (2.0 * PI * PI * sin_theta) } else { 0.0 }
    }

    /// The image coordinates a sample draws from two uniform numbers and the index of the
    /// texel drawn: the table reads, separate from [`texel_at`](Self::texel_at) and
    /// [`sampled`](Self::sampled) so that lanes can do each step for all of them at once.
    #[inline(always)]
    pub fn draw(&self, u: [f32; 2]) -> ([f32; 2], usize) {
        self.dist.draw(u)
    }

    /// The radiance of texel `index` and its density per du dv.
    #[inline(always)]
    pub fn texel_at(&self, index: usize) -> (Vec3, f32) {
        let t = self.texels[index];
        (t.rgb, t.pdf_uv)
    }

    /// What [`draw`](Self::draw) gave as a direction and its solid-angle density (zero: no
    /// sample).
    #[inline(always)]
    pub fn sampled(uv: [f32; 2], pdf_uv: f32) -> (Vec3, f32) {
        let (d, st) = Self::dir_sin_of(uv);
        (d, Self::solid_angle_pdf(pdf_uv, st))
    }

    /// A direction drawn by luminance x sin(theta), its solid-angle density and the radiance
    /// of the texel drawn: the three steps the light's samples take, in one call.
    #[cfg(test)]
    pub fn sample_texel(&self, u: [f32; 2]) -> Option<(Vec3, f32, Vec3)> {
        let (uv, index) = self.draw(u);
        let (l, pdf_uv) = self.texel_at(index);
        let (d, pdf) = Self::sampled(uv, pdf_uv);
        (pdf > 0.0).then_some((d, pdf, l))
    }

    /// Solid-angle density with which a light sample ([`draw`](Self::draw)) draws `d` (unit).
    #[inline]
    pub fn pdf(&self, d: Vec3) -> f32 {
        self.lookup(d).1
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::Sampler;

    #[test]
    fn cs184_orientation() {
        // theta from +Y; phi = atan2(-z, x) + pi.
        let close = |a: [f32; 2], b: [f32; 2]| (a[0] - b[0]).abs() < 1e-5 && (a[1] - b[1]).abs() < 1e-5;
        assert!(close(EnvMap::uv_of(Vec3::Y), [EnvMap::uv_of(Vec3::Y)[0], 0.0]));
        assert!(close(EnvMap::uv_of(Vec3::X), [0.5, 0.5]));
        assert!(close(EnvMap::uv_of(Vec3::Z), [0.25, 0.5]));
        assert!(close(EnvMap::uv_of(-Vec3::Z), [0.75, 0.5]));
        assert!((EnvMap::uv_of(-Vec3::Y)[1] - 1.0).abs() < 1e-6);
        let mut s = Sampler::for_sample(3, 0, 0);
        for _ in 0..1000 {
            let uv = [s.next_f32(), s.next_f32()];
            let back = EnvMap::uv_of(EnvMap::dir_of(uv));
            assert!((back[1] - uv[1]).abs() < 1e-4);
            if uv[1] > 0.01 && uv[1] < 0.99 {
                let du = (back[0] - uv[0]).abs();
                assert!(du < 1e-3 || (du - 1.0).abs() < 1e-3, "{uv:?} -> {back:?}");
            }
        }
    }

    /// The solid-angle pdf integrates to 1 over the sphere, and sampled directions carry the
    /// density `pdf()` reports.
    #[test]
    fn pdf_is_a_density_on_the_sphere() {
        let (w, h) = (16, 8);
        let texels: Vec<Vec3> =
            (0..w * h).map(|i| Vec3::splat(((i * 7) % 5) as f32 + if i == 37 { 50.0 } else { 0.0 })).collect();
        let m = EnvMap::from_texels("t".into(), w, h, texels).unwrap();
        // Midpoint rule on a fine (theta, phi) grid.
        let (nt, np) = (400, 800);
        let mut sum = 0.0f64;
        for i in 0..nt {
            for j in 0..np {
                let uv = [(j as f32 + 0.5) / np as f32, (i as f32 + 0.5) / nt as f32];
                let d = EnvMap::dir_of(uv);
                let dw = (PI / nt as f32) * (TAU / np as f32) * (uv[1] * PI).sin();
                sum += (m.pdf(d) * dw) as f64;
            }
        }
        assert!((sum - 1.0).abs() < 2e-3, "{sum}");
        let mut s = Sampler::for_sample(4, 0, 0);
        let mut other_texel = 0;
        for _ in 0..1000 {
            if let Some((d, p, l)) = m.sample_texel([s.next_f32(), s.next_f32()]) {
                assert!((p - m.pdf(d)).abs() < 1e-3 * p, "{p} vs {}", m.pdf(d));
                assert!(l.max_element() > 0.0, "sampled a black texel");
                // The carried radiance is the texel the direction falls in (but for rounding
                // right at a texel edge).
                other_texel += (l != m.radiance(d)) as u32;
            }
        }
        assert!(other_texel <= 3, "{other_texel} samples carried another texel's radiance");
    }

    #[test]
    fn bad_file_is_one_line_naming_it() {
        let e = EnvMap::load(Path::new("/nonexistent/map.exr")).unwrap_err().to_string();
        assert!(e.contains("/nonexistent/map.exr") && !e.contains('\n'), "{e}");
        let dir = std::env::temp_dir().join(format!("wavepath-envmap-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let f = dir.join("junk.hdr");
        std::fs::write(&f, b"#?RADIANCE\nnot really\n").unwrap();
        let e = EnvMap::load(&f).unwrap_err().to_string();
        assert!(e.contains("junk.hdr") && !e.contains('\n'), "{e}");
        std::fs::remove_dir_all(&dir).ok();
    }
}
