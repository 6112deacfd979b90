//! Which settings a sweep varies: each sweep is a set of curves, each curve one setting
//! rendered at a ladder of sample counts (or, for adaptive sampling, of tolerances), so
//! error against time shows which setting buys the most accuracy per second.

use wavepath::Settings;
use wavepath::{Aov, AovSet};
use wavepath::{IntegratorKind, Roulette, RouletteKind, SamplerKind, Shading};

/// The setting a study varies.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SweepKind {
    /// Samples per pixel 1, 2, 4, ... up to the cap: one curve.
    Spp,
    /// Samples per area light (-l) 1 ... 64, each over the spp ladder.
    LightSamples,
    /// Uniform hemisphere (-H) against light importance sampling, each over the spp ladder.
    Sampling,
    /// Maximum depth (-m) 1 ... 16, without Russian roulette and with it.
    Depth,
    /// Russian roulette continue probability at the deepest depth.
    Roulette,
    /// Adaptive sampling (-a 64 T) for T from 0.2 to 0.01, against fixed spp.
    Adaptive,
    /// Independent numbers, stratified and Sobol samples (`--sampler`), each over the spp
    /// ladder.
    Sampler,
    /// Light sampling combined with the BSDF's sample by MIS, against light sampling alone
    /// (`--no-mis`), each over the spp ladder.
    Mis,
    /// The raw render against the same render denoised by Open Image Denoise (fed its
    /// albedo and normal), over the spp ladder: two curves from one set of renders.
    Denoise,
    /// The path tracer against bidirectional path tracing and vertex connection and
    /// merging (`--integrator path|bdpt|vcm`), each over the spp ladder.
    Integrator,
}

impl SweepKind {
    pub fn name(self) -> &'static str {
        match self {
            SweepKind::Spp => "spp",
            SweepKind::LightSamples => "light-samples",
            SweepKind::Sampling => "sampling",
            SweepKind::Depth => "depth",
            SweepKind::Roulette => "roulette",
            SweepKind::Adaptive => "adaptive",
            SweepKind::Sampler => "sampler",
            SweepKind::Mis => "mis",
            SweepKind::Denoise => "denoise",
            SweepKind::Integrator => "integrator",
        }
    }

    /// Whether the sweep denoises its renders (and so needs Open Image Denoise).
    pub fn needs_denoiser(self) -> bool {
        self == SweepKind::Denoise
    }

    /// What a reader of the sweep's plot, CSV and report must know about its errors.
    pub fn note(self) -> Option<&'static str> {
        self.needs_denoiser().then_some(DENOISED_NOTE)
    }

    /// Whether this sweep judges against full transport at [`DEEP`] bounces rather than the
    /// base depth (its curves differ in bias, not only in noise).
    pub fn needs_deep_reference(self) -> bool {
        matches!(self, SweepKind::Depth | SweepKind::Roulette)
    }
}

/// The depth that stands for "all bounces" in the depth and roulette sweeps.
pub const DEEP: u32 = 16;
/// Batch size of the adaptive sweep (`-a 64 T`).
pub const ADAPTIVE_BATCH: u32 = 64;
/// Tolerances of the adaptive sweep.
pub const ADAPTIVE_TOLERANCES: [f32; 5] = [0.2, 0.1, 0.05, 0.02, 0.01];
/// The denoise sweep's warning: a denoised image is judged against the converged raw
/// reference (never a denoised one), and its error is mostly the denoiser's bias, which
/// more samples shrink but no variance predicts.
pub const DENOISED_NOTE: &str = "denoised: error against the converged raw reference (biased)";

/// How a curve's points are made.
#[derive(Clone, Debug, PartialEq)]
pub enum Ladder {
    /// The same settings at spp = 1, 2, 4, ... up to the cap.
    Spp,
    /// Adaptive sampling at each tolerance, spp = the cap.
    Tolerances(Vec<f32>),
    /// The renders of curve `of` denoised: no renders of its own; each point is one of that
    /// curve's renders, denoised, its time the render's plus the denoising's.
    Denoised { of: usize },
}

/// One curve of a sweep: a label, the settings it varies from the base, and its ladder.
#[derive(Clone, Debug, PartialEq)]
pub struct Curve {
    pub label: String,
    /// Short file-name-safe name.
    pub slug: String,
    pub settings: Settings,
    pub ladder: Ladder,
}

fn curve(label: String, slug: String, settings: Settings) -> Curve {
    Curve { label, slug, settings, ladder: Ladder::Spp }
}

/// The curves of `kind` around `base` (whose `spp` is ignored; the ladder sets it).
pub fn curves(kind: SweepKind, base: &Settings) -> Vec<Curve> {
    let b = || base.clone().with(|s| s.sampling.adaptive = None);
    match kind {
        SweepKind::Spp => {
            vec![curve(format!("-l {} -m {}", base.sampling.light_samples, base.paths.max_depth), "spp".into(), b())]
        }
        SweepKind::LightSamples => [1u32, 2, 4, 8, 16, 32, 64]
            .iter()
            .map(|&l| curve(format!("-l {l}"), format!("l{l}"), b().with(|s| s.sampling.light_samples = l)))
            .collect(),
        SweepKind::Sampling => vec![
            curve("light importance sampling".into(), "importance".into(), b().with(|s| s.paths.hemisphere = false)),
            curve("uniform hemisphere (-H)".into(), "hemisphere".into(), b().with(|s| s.paths.hemisphere = true)),
        ],
        SweepKind::Depth => {
            let mut out = Vec::new();
            for m in [1u32, 2, 4, 8, DEEP] {
                let s = depth_settings(&b(), m).with(|s| s.paths.roulette = fixed_roulette(base, 1.0));
                out.push(curve(format!("-m {m}, no roulette"), format!("m{m}"), s));
            }
            // With roulette: the base's own (the scene's default, or the --rr given).
            let (label, slug) = match base.paths.roulette.kind {
                RouletteKind::Fixed => {
                    let rr = base.paths.roulette.continue_prob;
                    (format!("--rr {rr}"), format!("rr{rr}"))
                }
                kind => (format!("{} roulette", kind.name()), kind.name().to_string()),
            };
            for m in [4u32, DEEP] {
                out.push(curve(format!("-m {m}, {label}"), format!("m{m}-{slug}"), depth_settings(&b(), m)));
            }
            out
        }
        SweepKind::Roulette => [1.0f32, 0.9, 0.8, 0.65, 0.5, 0.3, 0.1]
            .iter()
            .map(|&rr| {
                let label = if rr == 1.0 { format!("-m {DEEP}, no roulette") } else { format!("-m {DEEP}, --rr {rr}") };
                let s = depth_settings(&b(), DEEP).with(|s| s.paths.roulette = fixed_roulette(base, rr));
                curve(label, format!("rr{rr}"), s)
            })
            .collect(),
        SweepKind::Sampler => SamplerKind::ALL
            .iter()
            .map(|&k| curve(format!("--sampler {}", k.name()), k.name().into(), b().with(|s| s.sampling.sampler = k)))
            .collect(),
        SweepKind::Mis => vec![
            curve("MIS (light + BSDF samples)".into(), "mis".into(), b().with(|s| s.paths.mis = true)),
            curve("light sampling alone (--no-mis)".into(), "no-mis".into(), b().with(|s| s.paths.mis = false)),
        ],
        SweepKind::Integrator => [
            (IntegratorKind::Wavefront, "path tracer"),
            (IntegratorKind::Bdpt, "bidirectional (BDPT)"),
            (IntegratorKind::Vcm, "connection and merging (VCM)"),
            (IntegratorKind::PathLight, "path tracer plus light tracing"),
        ]
        .iter()
        .map(|&(k, what)| {
            let name = if k == IntegratorKind::Wavefront { "path" } else { k.name() };
            curve(format!("--integrator {name}: {what}"), name.into(), b().with(|s| s.execution.integrator = k))
        })
        .collect(),
        SweepKind::Denoise => {
            let s = b().with(|s| s.image.aovs = s.image.aovs.union(denoiser_aovs()));
            vec![
                curve("raw".into(), "raw".into(), s.clone()),
                Curve {
                    label: "denoised (OIDN, albedo + normal)".into(),
                    slug: "denoised".into(),
                    settings: s,
                    ladder: Ladder::Denoised { of: 0 },
                },
            ]
        }
        SweepKind::Adaptive => vec![
            curve("fixed spp".into(), "fixed".into(), b()),
            Curve {
                label: format!("adaptive -a {ADAPTIVE_BATCH} T"),
                slug: "adaptive".into(),
                settings: b(),
                ladder: Ladder::Tolerances(ADAPTIVE_TOLERANCES.to_vec()),
            },
        ],
    }
}

/// The output variables the denoise sweep's renders keep for the denoiser.
pub fn denoiser_aovs() -> AovSet {
    AovSet::NONE.with(Aov::Albedo).with(Aov::Normal)
}

/// `b` at depth `m`, showing what a render at that depth shows.
fn depth_settings(b: &Settings, m: u32) -> Settings {
    b.clone().with(|s| {
        s.paths.max_depth = m;
        s.paths.shading = Shading::for_depth(m)
    })
}

/// Fixed roulette with continue probability `rr` (1: none), the value the roulette sweep
/// varies: a base of another kind (a scene whose default is throughput roulette) switches
/// to the fixed rule and its start depth, as `--roulette fixed` does; a fixed base keeps its
/// start.
fn fixed_roulette(base: &Settings, rr: f32) -> Roulette {
    let r = base.paths.roulette;
    let start_depth =
        if r.kind == RouletteKind::Fixed { r.start_depth } else { RouletteKind::Fixed.default_start_depth() };
    Roulette { kind: RouletteKind::Fixed, continue_prob: rr, start_depth }
}

/// Sample counts of the spp ladder: powers of two up to `cap` (and `cap` itself).
pub fn spp_ladder(cap: u32) -> Vec<u32> {
    let cap = cap.max(1);
    let mut v: Vec<u32> = (0..31).map(|i| 1u32 << i).take_while(|&s| s <= cap).collect();
    if *v.last().unwrap_or(&0) != cap {
        v.push(cap);
    }
    v
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ladder_is_powers_of_two_up_to_the_cap() {
        assert_eq!(spp_ladder(1), vec![1]);
        assert_eq!(spp_ladder(16), vec![1, 2, 4, 8, 16]);
        assert_eq!(spp_ladder(20), vec![1, 2, 4, 8, 16, 20]);
    }

    /// A scene whose default is throughput roulette keeps it in every curve but those whose
    /// swept value is the roulette: the depth sweep's curves without roulette, and the
    /// roulette sweep's fixed probabilities.
    #[test]
    fn curves_change_the_roulette_only_where_they_sweep_it() {
        let base = Settings::for_dialect(wavepath::Dialect::Standard).with(|s| s.paths.max_depth = 5);
        assert_eq!(base.paths.roulette.kind, RouletteKind::Throughput);
        for k in [
            SweepKind::Spp,
            SweepKind::LightSamples,
            SweepKind::Sampling,
            SweepKind::Adaptive,
            SweepKind::Mis,
            SweepKind::Denoise,
        ] {
            assert!(curves(k, &base).iter().all(|c| c.settings.paths.roulette == base.paths.roulette), "{k:?}");
        }
        for c in curves(SweepKind::Depth, &base) {
            let want = if c.label.contains("no roulette") { fixed_roulette(&base, 1.0) } else { base.paths.roulette };
            assert_eq!(c.settings.paths.roulette, want, "{}", c.label);
        }
        for c in curves(SweepKind::Roulette, &base) {
            let r = c.settings.paths.roulette;
            assert_eq!((r.kind, r.start_depth), (RouletteKind::Fixed, 1), "{}", c.label);
        }
    }

    #[test]
    fn every_sweep_has_curves_with_distinct_slugs() {
        let mut base = Settings::default();
        base.paths.max_depth = 5;
        for k in [
            SweepKind::Spp,
            SweepKind::LightSamples,
            SweepKind::Sampling,
            SweepKind::Depth,
            SweepKind::Roulette,
            SweepKind::Adaptive,
            SweepKind::Sampler,
            SweepKind::Mis,
            SweepKind::Denoise,
        ] {
            let c = curves(k, &base);
            assert!(!c.is_empty());
            let mut slugs: Vec<_> = c.iter().map(|c| c.slug.clone()).collect();
            slugs.sort();
            slugs.dedup();
            assert_eq!(slugs.len(), c.len(), "{k:?}");
        }
    }
}
