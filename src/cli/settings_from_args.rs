//! Checks every flag's range and turns the arguments into [`Settings`].

use super::RenderArgs;
use anyhow::{Result, bail};
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

/// The flags applied on top of `base`, normally [`Settings::for_scene`] of the loaded scene:
/// a flag the user gave overrides the dialect's default, one left out keeps it.
pub fn settings(a: &RenderArgs, base: Settings) -> Result<Settings> {
    let mut s = base;
    if let Some(r) = &a.resolution {
        let w = in_range("-r width", r[0], 1, MAX_SIDE)?;
        let h = in_range("-r height", r[1], 1, MAX_SIDE)?;
        if w * h > MAX_PIXELS {
            bail!("-r {w} {h} is {} pixels, more than the limit of {MAX_PIXELS}", w * h);
        }
        s.image.width = w as usize;
        s.image.height = h as usize;
    }
    s.sampling.spp = in_range("-s (samples per pixel)", a.spp, 1, 1 << 20)? as u32;
    s.sampling.light_samples = in_range("-l (samples per area light)", a.light_samples, 1, 1 << 16)? as u32;
    s.paths.max_depth = in_range("-m (maximum ray depth)", a.max_depth, 0, 1 << 12)? as u32;
    s.paths.accumulate = match a.accumulate {
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
        s.sampling.adaptive = Some((b as u32, t as f32));
    }
    if let Some(t) = a.threads {
        s.execution.threads = in_range("-t (threads)", t, 1, 4096)? as usize;
    }
    if !(a.rr.is_finite() && a.rr > 0.0 && a.rr <= 1.0) {
        bail!("--rr must be in (0, 1], got {}", a.rr);
    }
    let roulette = &mut s.paths.roulette;
    roulette.continue_prob = a.rr as f32;
    // `--roulette` chooses the kind and with it that kind's start depth; `--rr-depth` the
    // depth alone; without either, the dialect's defaults stand.
    if let Some(kind) = a.roulette {
        roulette.kind = kind.into();
        roulette.start_depth = roulette.kind.default_start_depth();
    }
    if let Some(d) = a.rr_depth {
        roulette.start_depth = in_range("--rr-depth", d, 1, 1 << 16)? as u32;
    }
    s.paths.hemisphere = a.hemisphere;
    s.accel.use_bvh = !a.no_bvh;
    s.accel.bvh = BvhOptions { build: a.bvh_build.into(), leaves: a.bvh_leaves.into() };
    s.execution.isa = a.isa;
    s.sampling.seed = a.seed;
    s.execution.integrator = a.integrator.into();
    s.execution.all_effects = a.all_effects;
    s.cs184.light_pdf = a.cs184_light_pdf;
    s.paths.mis = !a.no_mis;
    if let Some(sampler) = a.sampler {
        s.sampling.sampler = sampler.into();
    }
    s.paths.shading = a.shading.map(Shading::from).unwrap_or(Shading::for_depth(s.paths.max_depth));
    if let Some(p) = &a.cell {
        for (name, v) in ["X", "Y", "DX", "DY"].iter().zip(p) {
            in_range(&format!("-p {name}"), *v, 0, MAX_SIDE)?;
        }
        let cell = Cell { x: p[0] as usize, y: p[1] as usize, w: p[2] as usize, h: p[3] as usize };
        let (w, h) = (s.image.width, s.image.height);
        if cell.w == 0 || cell.h == 0 || cell.x >= w || cell.y >= h {
            bail!("-p {} {} {} {} lies outside the {w}x{h} image", p[0], p[1], p[2], p[3]);
        }
        s.image.cell = Some(cell);
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
