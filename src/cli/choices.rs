//! The command line's choices. The engine's settings are parsed by the engine's own names
//! ([`named`]: clap lists and parses them through `wavepath::Choice`, so a name means the
//! same here as in Python and the viewer); the applications' own choices get a clap twin.

use clap::builder::{PossibleValue, TypedValueParser};
use std::marker::PhantomData;
use wavepath::Choice;

/// The clap parser of an engine setting chosen by name: the engine's names (with their help
/// lines) in `--help`, the engine's message for an unknown one under the flag's name.
pub fn named<T: Choice + Send + Sync>() -> Named<T> {
    Named(PhantomData)
}

/// See [`named`].
#[derive(Clone, Copy, Debug)]
pub struct Named<T>(PhantomData<fn() -> T>);

impl<T: Choice + Send + Sync> TypedValueParser for Named<T> {
    type Value = T;

    fn parse_ref(
        &self,
        _cmd: &clap::Command,
        arg: Option<&clap::Arg>,
        value: &std::ffi::OsStr,
    ) -> Result<T, clap::Error> {
        let flag = arg.and_then(|a| a.get_long().map(|l| format!("--{l}")));
        let flag = flag.unwrap_or_else(|| T::SETTING.to_string());
        T::from_name(&value.to_string_lossy())
            .map_err(|e| clap::Error::raw(clap::error::ErrorKind::InvalidValue, format!("{}\n", e.for_option(&flag))))
    }

    fn possible_values(&self) -> Option<Box<dyn Iterator<Item = PossibleValue> + '_>> {
        Some(Box::new(T::ALL.iter().map(|v| PossibleValue::new(v.name()).help(v.help()))))
    }
}

/// A clap value enum mirroring a library enum variant by variant.
macro_rules! choice {
    ($(#[$doc:meta])* $name:ident => $lib:path { $($(#[$vdoc:meta])* $variant:ident),+ $(,)? }) => {
        $(#[$doc])*
        #[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
        pub enum $name {
            $($(#[$vdoc])* $variant),+
        }

        impl From<$name> for $lib {
            fn from(c: $name) -> $lib {
                match c {
                    $($name::$variant => <$lib>::$variant),+
                }
            }
        }
    };
}

choice! {
    /// How a render is cut into parts.
    Split => wavepath_apps::parts::Split {
        /// Bands of rows, dealt round-robin to the parts: every pixel is rendered by one part
        /// exactly as a single process renders it, so the merge is bit-identical.
        Tiles,
        /// Every part renders every pixel with its own range of sample indices; the merge adds
        /// the per-pixel sums (identical up to floating-point summation order).
        Samples,
    }
}

choice! {
    /// The setting a study varies.
    Sweep => wavepath_apps::study::SweepKind {
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
        /// Independent numbers, stratified and Sobol samples, each over the spp ladder.
        Sampler,
        /// MIS of light and BSDF samples against light sampling alone (--no-mis).
        Mis,
        /// Each render raw and denoised (Open Image Denoise, albedo + normal), both against
        /// the raw reference (the denoised error is biased).
        Denoise,
        /// The path tracer against BDPT and VCM (--integrator path|bdpt|vcm).
        Integrator,
    }
}
