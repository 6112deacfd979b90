//! What a caller asks of a render, checked in one place. The command line, the Python
//! package, the viewer and studies take the same values under their own names (`-s`,
//! `spp=`, `spp=` in a query); each hands its values here, so a bad value gets the same
//! message everywhere but for the option's name, and the same values give the same
//! [`Settings`] (the rules that turn a request into settings, such as the shading that
//! follows the depth or the roulette start that follows its kind, live here too).

use crate::cpu::Isa;
use crate::sampling::SamplerKind;
use crate::scene::{Camera, FovRule};
use crate::settings::{BvhBuild, Cell, IntegratorKind, LeafLayout, RouletteKind, Settings, Shading};
use std::fmt;

/// Largest image side accepted; beyond this a typo is far more likely than a real render.
pub const MAX_SIDE: u32 = 1 << 15;
/// Largest number of pixels accepted (a 16K x 16K image).
pub const MAX_PIXELS: u64 = 1 << 28;

/// A value of a request that has a range, named in messages by what it is; the option's
/// name is the front end's (`-s`, `spp`), passed in with the value.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Field {
    Width,
    Height,
    Spp,
    LightSamples,
    MaxDepth,
    /// All bounces (1) or only the last (0), as the CS184 `-o` flag takes it.
    Accumulate,
    AdaptiveBatch,
    AdaptiveTolerance,
    Threads,
    ContinueProb,
    RouletteStart,
    CellX,
    CellY,
    CellWidth,
    CellHeight,
    LensRadius,
    FocalDistance,
    LightPaths,
}

/// Most light subpaths per pixel and sample (`--light-paths`): more only multiplies the time.
pub const MAX_LIGHT_PATHS: f64 = 64.0;

/// The values a field takes.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Range {
    /// A whole number in `[lo, hi]`.
    Whole(i64, i64),
    /// A finite number above 0.
    Positive,
    /// A finite number of at least 0.
    NonNegative,
    /// A continue probability, in (0, 1].
    Probability,
}

impl Field {
    /// What the value is, in words: the message puts it beside the option's name, so that
    /// `-m` or `max_depth` is explained the same way everywhere.
    pub fn what(self) -> &'static str {
        match self {
            Field::Width => "image width",
            Field::Height => "image height",
            Field::Spp => "samples per pixel",
            Field::LightSamples => "samples per area light",
            Field::MaxDepth => "maximum ray depth",
            Field::Accumulate => "accumulate bounces",
            Field::AdaptiveBatch => "batch size",
            Field::AdaptiveTolerance => "tolerance",
            Field::Threads => "worker threads, 0 for all cores",
            Field::ContinueProb => "continue probability",
            Field::RouletteStart => "first depth of roulette",
            Field::CellX => "cell x",
            Field::CellY => "cell y",
            Field::CellWidth => "cell width",
            Field::CellHeight => "cell height",
            Field::LensRadius => "lens radius",
            Field::FocalDistance => "focal distance",
            Field::LightPaths => "light subpaths per pixel and sample",
        }
    }

    /// The values accepted: wide enough for any real render, narrow enough that a typo
    /// (an extra digit, a sign) is refused before it costs hours or all the memory.
    pub fn range(self) -> Range {
        let side = MAX_SIDE as i64;
        match self {
            Field::Width | Field::Height => Range::Whole(1, side),
            Field::Spp => Range::Whole(1, 1 << 20),
            Field::LightSamples => Range::Whole(1, 1 << 16),
            Field::MaxDepth => Range::Whole(0, 1 << 12),
            Field::Accumulate => Range::Whole(0, 1),
            Field::AdaptiveBatch => Range::Whole(1, 1 << 20),
            Field::AdaptiveTolerance | Field::FocalDistance | Field::LightPaths => Range::Positive,
            Field::Threads => Range::Whole(0, 4096),
            Field::ContinueProb => Range::Probability,
            Field::RouletteStart => Range::Whole(1, 1 << 16),
            Field::CellX | Field::CellY | Field::CellWidth | Field::CellHeight => Range::Whole(0, side),
            Field::LensRadius => Range::NonNegative,
        }
    }

    /// A whole number given for this field (`-s 4`, `spp=4`), if it is in range; else the
    /// message naming `option` and the value given.
    pub fn whole(self, option: &str, v: i64) -> Result<u32, InvalidValue> {
        match self.range() {
            Range::Whole(lo, hi) if (lo..=hi).contains(&v) => Ok(v as u32),
            Range::Whole(0, 1) => Err(self.invalid(option, "must be 0 or 1", v)),
            Range::Whole(lo, hi) => Err(self.invalid(option, &format!("must be between {lo} and {hi}"), v)),
            _ => self.number(option, v as f64).map(|x| x as u32),
        }
    }

    /// A number given for this field (`--rr 0.5`, `-a 64 0.05`), if it is in range; a whole
    /// field takes a number without a fraction.
    pub fn number(self, option: &str, v: f64) -> Result<f64, InvalidValue> {
        let (ok, rule) = match self.range() {
            Range::Whole(lo, hi) => (
                v.is_finite() && v.fract() == 0.0 && v >= lo as f64 && v <= hi as f64,
                format!("must be a whole number between {lo} and {hi}"),
            ),
            Range::Positive => (v.is_finite() && v > 0.0, "must be a positive number".into()),
            Range::NonNegative => (v.is_finite() && v >= 0.0, "must be a non-negative number".into()),
            Range::Probability => (v.is_finite() && v > 0.0 && v <= 1.0, "must be in (0, 1]".into()),
        };
        if ok { Ok(v) } else { Err(self.invalid(option, &rule, v)) }
    }

    fn invalid(self, option: &str, rule: &str, v: impl fmt::Display) -> InvalidValue {
        InvalidValue(format!("{option} ({}) {rule}, got {v}", self.what()))
    }
}

/// An image size, `option` being the front end's name for it (`-r`, `resolution`): each
/// side in range and the pixels within [`MAX_PIXELS`].
pub fn check_resolution(option: &str, width: i64, height: i64) -> Result<(usize, usize), InvalidValue> {
    let w = Field::Width.whole(option, width)?;
    let h = Field::Height.whole(option, height)?;
    let pixels = w as u64 * h as u64;
    if pixels > MAX_PIXELS {
        return Err(InvalidValue(format!("{option} {w}x{h} is {pixels} pixels, more than the limit of {MAX_PIXELS}")));
    }
    Ok((w as usize, h as usize))
}

/// A value of a request out of its range; the message names the option as the front end
/// spells it and the value the user gave.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct InvalidValue(String);

impl fmt::Display for InvalidValue {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for InvalidValue {}

/// A front end's name for each field (`-s` for [`Field::Spp`] on the command line, `spp`
/// in Python).
pub type Names = fn(Field) -> &'static str;

/// A render request as a user gives it: each value `None` where the user left it out (the
/// base settings' value then stands, as a flag left out keeps the dialect's default), and
/// numbers as typed (whole numbers `i64`, others `f64`) so that a value out of range is
/// reported as the user wrote it.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Request {
    /// Width and height in pixels (`-r W H`).
    pub resolution: Option<(i64, i64)>,
    /// Only this rectangle of the image, `[x, y, width, height]` (`-p`).
    pub cell: Option<[i64; 4]>,
    pub spp: Option<i64>,
    pub light_samples: Option<i64>,
    /// Batch size and tolerance of adaptive sampling (`-a B T`).
    pub adaptive: Option<(f64, f64)>,
    pub sampler: Option<SamplerKind>,
    pub seed: Option<u64>,
    pub max_depth: Option<i64>,
    /// 1: all bounces, 0: only the last (`-o`).
    pub accumulate: Option<i64>,
    /// `None`: [`Shading::for_depth`] of the depth.
    pub shading: Option<Shading>,
    pub hemisphere: Option<bool>,
    pub mis: Option<bool>,
    /// The roulette's kind, and with it that kind's start depth unless `rr_depth` is given.
    pub roulette: Option<RouletteKind>,
    /// The fixed roulette's continue probability (`--rr`).
    pub rr: Option<f64>,
    pub rr_depth: Option<i64>,
    /// `false`: brute force (`--no-bvh`).
    pub use_bvh: Option<bool>,
    pub bvh_build: Option<BvhBuild>,
    pub bvh_leaves: Option<LeafLayout>,
    /// Worker threads, 0 for all cores.
    pub threads: Option<i64>,
    pub integrator: Option<IntegratorKind>,
    pub isa: Option<Isa>,
    pub all_effects: Option<bool>,
    pub cs184_light_pdf: Option<bool>,
    /// How a CS184 camera's field of view follows the resolution (the settings' `image.fov`).
    pub fov: Option<FovRule>,
    pub lens_radius: Option<f64>,
    pub focal_distance: Option<f64>,
    /// Light subpaths per pixel and sample of light tracing and `path+light`.
    pub light_paths: Option<f64>,
    /// Output variables kept beside the picture (`--aov`).
    pub aovs: Option<crate::settings::AovSet>,
}

impl Request {
    /// `base` (normally [`Settings::for_scene`] of the scene) with every value given
    /// applied, or the first value out of range, named by `names`. The lens values are
    /// checked here too ([`Request::camera`] applies them).
    pub fn apply(&self, base: Settings, names: Names) -> Result<Settings, InvalidValue> {
        let mut s = base;
        if let Some((w, h)) = self.resolution {
            (s.image.width, s.image.height) = check_resolution(names(Field::Width), w, h)?;
        }
        let whole = |f: Field, v: Option<i64>| v.map(|v| f.whole(names(f), v)).transpose();
        if let Some(v) = whole(Field::Spp, self.spp)? {
            s.sampling.spp = v;
        }
        if let Some(v) = whole(Field::LightSamples, self.light_samples)? {
            s.sampling.light_samples = v;
        }
        if let Some(v) = self.light_paths {
            let v = Field::LightPaths.number(names(Field::LightPaths), v)?;
            if v > MAX_LIGHT_PATHS {
                return Err(Field::LightPaths.invalid(
                    names(Field::LightPaths),
                    &format!("must be at most {MAX_LIGHT_PATHS}"),
                    v,
                ));
            }
            s.sampling.light_paths = Some(v as f32);
        }
        if let Some(v) = whole(Field::MaxDepth, self.max_depth)? {
            s.paths.max_depth = v;
        }
        if let Some(v) = whole(Field::Accumulate, self.accumulate)? {
            s.paths.accumulate = v == 1;
        }
        if let Some((b, t)) = self.adaptive {
            let b = Field::AdaptiveBatch.number(names(Field::AdaptiveBatch), b)?;
            let t = Field::AdaptiveTolerance.number(names(Field::AdaptiveTolerance), t)?;
            s.sampling.adaptive = Some((b as u32, t as f32));
        }
        if let Some(v) = whole(Field::Threads, self.threads)? {
            s.execution.threads = v as usize;
        }
        if let Some(p) = self.rr {
            s.paths.roulette.continue_prob = Field::ContinueProb.number(names(Field::ContinueProb), p)? as f32;
        }
        // The kind chooses its start depth (the fixed rule from the first indirect bounce,
        // throughput from depth 5); `rr_depth` overrides it; without either the base's stand.
        if let Some(kind) = self.roulette {
            s.paths.roulette.kind = kind;
            s.paths.roulette.start_depth = kind.default_start_depth();
        }
        if let Some(d) = whole(Field::RouletteStart, self.rr_depth)? {
            s.paths.roulette.start_depth = d;
        }
        set(&mut s.paths.hemisphere, self.hemisphere);
        set(&mut s.paths.mis, self.mis);
        set(&mut s.accel.use_bvh, self.use_bvh);
        set(&mut s.accel.bvh.build, self.bvh_build);
        set(&mut s.accel.bvh.leaves, self.bvh_leaves);
        set(&mut s.execution.isa, self.isa);
        set(&mut s.execution.integrator, self.integrator);
        set(&mut s.execution.all_effects, self.all_effects);
        set(&mut s.cs184.light_pdf, self.cs184_light_pdf);
        set(&mut s.sampling.seed, self.seed);
        set(&mut s.sampling.sampler, self.sampler);
        set(&mut s.image.fov, self.fov);
        set(&mut s.image.aovs, self.aovs);
        // Direct light alone at depth 1, global illumination beyond, unless named.
        s.paths.shading = self.shading.unwrap_or(Shading::for_depth(s.paths.max_depth));
        if let Some(p) = self.cell {
            let option = names(Field::CellX);
            let fields = [Field::CellX, Field::CellY, Field::CellWidth, Field::CellHeight];
            for (f, v) in fields.into_iter().zip(p) {
                f.whole(option, v)?;
            }
            let cell = Cell { x: p[0] as usize, y: p[1] as usize, w: p[2] as usize, h: p[3] as usize };
            let (w, h) = (s.image.width, s.image.height);
            if cell.w == 0 || cell.h == 0 || cell.x >= w || cell.y >= h {
                return Err(InvalidValue(format!(
                    "{option} {} {} {} {} lies outside the {w}x{h} image",
                    p[0], p[1], p[2], p[3]
                )));
            }
            s.image.cell = Some(cell);
        }
        if s.image.aovs.traced()
            && !matches!(
                s.execution.integrator,
                IntegratorKind::Auto | IntegratorKind::Wavefront | IntegratorKind::PathLight
            )
        {
            return Err(InvalidValue(format!(
                "the output variables {} need the wavefront integrator: {} records no first hits",
                s.image.aovs,
                s.execution.integrator.name()
            )));
        }
        if !s.image.aovs.is_empty() && s.paths.shading == Shading::Normals {
            return Err(InvalidValue(format!(
                "the normals view keeps no output variables ({}); render light transport",
                s.image.aovs
            )));
        }
        if let Some(r) = self.lens_radius {
            Field::LensRadius.number(names(Field::LensRadius), r)?;
        }
        if let Some(d) = self.focal_distance {
            Field::FocalDistance.number(names(Field::FocalDistance), d)?;
        }
        Ok(s)
    }

    /// `cam` with the lens values given. The lens is the camera's, whatever the image; its
    /// fit to the image is not applied here but by the render plan, from the settings'
    /// field-of-view rule ([`Request::apply`] sets it).
    pub fn camera(&self, cam: Camera) -> Camera {
        let mut cam = cam;
        if let Some(r) = self.lens_radius {
            cam.lens_radius = r as f32;
        }
        if let Some(d) = self.focal_distance {
            cam.focal_distance = d as f32;
        }
        cam
    }
}

fn set<T>(field: &mut T, v: Option<T>) {
    if let Some(v) = v {
        *field = v;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn flag(f: Field) -> &'static str {
        match f {
            Field::Width | Field::Height => "-r",
            Field::Spp => "-s",
            Field::ContinueProb => "--rr",
            Field::CellX | Field::CellY | Field::CellWidth | Field::CellHeight => "-p",
            _ => "-x",
        }
    }

    fn refused(r: Request) -> String {
        r.apply(Settings::default(), flag).unwrap_err().to_string()
    }

    #[test]
    fn values_out_of_range_name_the_option_and_the_value() {
        let r = Request::default;
        assert_eq!(
            refused(Request { resolution: Some((0, 10)), ..r() }),
            "-r (image width) must be between 1 and 32768, got 0"
        );
        assert_eq!(
            refused(Request { resolution: Some((10, 100000)), ..r() }),
            "-r (image height) must be between 1 and 32768, got 100000"
        );
        assert_eq!(
            refused(Request { resolution: Some((20000, 20000)), ..r() }),
            "-r 20000x20000 is 400000000 pixels, more than the limit of 268435456"
        );
        assert_eq!(
            refused(Request { spp: Some(0), ..r() }),
            "-s (samples per pixel) must be between 1 and 1048576, got 0"
        );
        assert_eq!(refused(Request { rr: Some(1.5), ..r() }), "--rr (continue probability) must be in (0, 1], got 1.5");
        assert_eq!(
            refused(Request { rr: Some(f64::NAN), ..r() }),
            "--rr (continue probability) must be in (0, 1], got NaN"
        );
        assert_eq!(refused(Request { accumulate: Some(2), ..r() }), "-x (accumulate bounces) must be 0 or 1, got 2");
        assert_eq!(
            refused(Request { adaptive: Some((0.5, 0.1)), ..r() }),
            "-x (batch size) must be a whole number between 1 and 1048576, got 0.5"
        );
        assert_eq!(
            refused(Request { cell: Some([50, 0, 10, 10]), resolution: Some((40, 30)), ..r() }),
            "-p 50 0 10 10 lies outside the 40x30 image"
        );
        assert_eq!(Field::Threads.whole("-t", 0), Ok(0), "0 threads: all cores");
    }

    #[test]
    fn a_request_applies_the_front_ends_rules() {
        let base = Settings::for_dialect(crate::cs184::Dialect::Standard);
        let s = Request { max_depth: Some(1), ..Request::default() }.apply(base.clone(), flag).unwrap();
        assert_eq!(s.paths.shading, Shading::Direct);
        assert_eq!(s.paths.roulette, base.paths.roulette, "left out, the dialect's roulette stands");
        let fixed = Request { roulette: Some(RouletteKind::Fixed), rr: Some(0.5), ..Request::default() };
        let s = fixed.apply(base.clone(), flag).unwrap();
        assert_eq!(
            (s.paths.roulette.kind, s.paths.roulette.continue_prob, s.paths.roulette.start_depth),
            (RouletteKind::Fixed, 0.5, 1)
        );
        let later = Request { rr_depth: Some(3), ..fixed };
        assert_eq!(later.apply(base, flag).unwrap().paths.roulette.start_depth, 3);
    }
}
