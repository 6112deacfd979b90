//! Checks every flag's range and turns the arguments into [`Settings`].

use super::RenderArgs;
use super::choices::Roulette;
use anyhow::{Result, bail};
use wavepath::SamplerKind;
use wavepath::{BvhOptions, Cell, Settings, Shading};

/// Largest image side accepted; beyond this a typo is far more likely than a real render.
pub const MAX_SIDE: i64 = 1 << 15;
/// Largest number of pixels accepted (a 16K x 16K image).
pub const MAX_PIXELS: i64 = 1 << 28;

fn in_range(name: &str, v: i64, lo: i64, hi: i64) -> Result<i64> {
    if v < lo || v > hi {
        bail!("{name} must be between {lo} and {hi}, got {v}");
    }
    Ok(v)
}

pub fn settings(a: &RenderArgs) -> Result<Settings> {
    let mut s = Settings::default();
    if let Some(r) = &a.resolution {
        let w = in_range("-r width", r[0], 1, MAX_SIDE)?;
        let h = in_range("-r height", r[1], 1, MAX_SIDE)?;
        if w * h > MAX_PIXELS {
            bail!("-r {w} {h} is {} pixels, more than the limit of {MAX_PIXELS}", w * h);
        }
        s.width = w as usize;
        s.height = h as usize;
    }
    s.spp = in_range("-s (samples per pixel)", a.spp, 1, 1 << 20)? as u32;
    s.light_samples = in_range("-l (samples per area light)", a.light_samples, 1, 1 << 16)? as u32;
    s.max_depth = in_range("-m (maximum ray depth)", a.max_depth, 0, 1 << 12)? as u32;
    s.accumulate = match a.accumulate {
        0 => false,
        1 => true,
        v => bail!("-o must be 0 or 1, got {v}"),
    };
    if let Some(ad) = &a.adaptive {
        let (b, t) = (ad[0], ad[1]);
        if !(b.is_finite() && b >= 1.0 && b <= (1u32 << 20) as f64 && b.fract() == 0.0) {
            bail!("-a batch size must be a whole number between 1 and {}, got {b}", 1u32 << 20);
        }
        if !(t.is_finite() && t > 0.0) {
            bail!("-a tolerance must be a positive number, got {t}");
        }
        s.adaptive = Some((b as u32, t as f32));
    }
    if let Some(t) = a.threads {
        s.threads = in_range("-t (threads)", t, 1, 4096)? as usize;
    }
    if !(a.rr.is_finite() && a.rr > 0.0 && a.rr <= 1.0) {
        bail!("--rr must be in (0, 1], got {}", a.rr);
    }
    s.rr_continue = a.rr as f32;
    // The seed's fixed roulette for its own scenes; for other files the estimator that reached
    // a given error soonest in the end-to-end harness (docs/decisions.md, "Russian roulette").
    let cs184 = is_cs184(a.scene.as_deref());
    let roulette = a.roulette.unwrap_or(if cs184 { Roulette::Fixed } else { Roulette::Throughput });
    s.rr_throughput = roulette == Roulette::Throughput;
    s.rr_depth = match a.rr_depth {
        Some(d) => in_range("--rr-depth", d, 1, 1 << 16)? as u32,
        None if s.rr_throughput => 5,
        None => 1,
    };
    s.hemisphere = a.hemisphere;
    s.use_bvh = !a.no_bvh;
    s.bvh = BvhOptions { build: a.bvh_build.into(), leaves: a.bvh_leaves.into() };
    s.isa = a.isa;
    s.seed = a.seed;
    s.integrator = a.integrator.into();
    s.all_effects = a.all_effects;
    s.cs184_light_pdf = a.cs184_light_pdf;
    s.mis = !a.no_mis;
    s.sampler = a.sampler.map(Into::into).unwrap_or(default_sampler(a.scene.as_deref()));
    s.shading = a.shading.map(Shading::from).unwrap_or(if s.max_depth > 1 { Shading::Global } else { Shading::Direct });
    if let Some(p) = &a.cell {
        for (name, v) in ["X", "Y", "DX", "DY"].iter().zip(p) {
            in_range(&format!("-p {name}"), *v, 0, MAX_SIDE)?;
        }
        let cell = Cell { x: p[0] as usize, y: p[1] as usize, w: p[2] as usize, h: p[3] as usize };
        if cell.w == 0 || cell.h == 0 || cell.x >= s.width || cell.y >= s.height {
            bail!("-p {} {} {} {} lies outside the {}x{} image", p[0], p[1], p[2], p[3], s.width, s.height);
        }
        s.cell = Some(cell);
    }
    if let Some(b) = a.lens_radius
        && !(b.is_finite() && b >= 0.0)
    {
        bail!("-b (lens radius) must be a non-negative number, got {b}");
    }
    if let Some(d) = a.focal_distance
        && !(d.is_finite() && d > 0.0)
    {
        bail!("-d (focal distance) must be a positive number, got {d}");
    }
    Ok(s)
}

/// The sampler of a render of `scene` (`None`: the embedded one) without `--sampler`:
/// independent numbers keep the seed's pictures (.dae files and the embedded scene); other
/// files get the pattern that reached a given error soonest in the end-to-end harness
/// (docs/decisions.md, "Samplers").
pub fn default_sampler(scene: Option<&std::path::Path>) -> SamplerKind {
    if is_cs184(scene) { SamplerKind::Independent } else { SamplerKind::Sobol }
}

/// Whether `scene` is one of the seed's own (a .dae file, or `None`: the embedded scene).
fn is_cs184(scene: Option<&std::path::Path>) -> bool {
    scene.is_none_or(|p| p.extension().is_some_and(|e| e.eq_ignore_ascii_case("dae")))
}
