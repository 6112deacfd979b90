//! Settings chosen by name. The command line (`--sampler sobol`), the Python package
//! (`sampler="sobol"`) and the viewer (`shading=direct`) all read a name into one of the
//! engine's enums; each enum lists its names here once ([`named!`]), so every front end
//! accepts the same names and refuses an unknown one with the same message.

use std::fmt;

/// A setting whose values are chosen by name.
pub trait Choice: Copy + Sized + 'static {
    /// What the setting is, for a message that has no option name to give.
    const SETTING: &'static str;
    /// Every value, in the order their names are listed.
    const ALL: &'static [Self];

    /// The value's name, as every front end spells it.
    fn name(self) -> &'static str;

    /// One line on what the value does (the command line's help shows it beside the name).
    fn help(self) -> &'static str;

    /// Other spellings accepted for this value, never listed (older names, common variants).
    fn aliases(self) -> &'static [&'static str] {
        &[]
    }

    /// The value named `s`; case and surrounding blanks do not matter, since a name is
    /// often typed by hand.
    fn from_name(s: &str) -> Result<Self, UnknownName> {
        let t = s.trim();
        let is = |n: &str| n.eq_ignore_ascii_case(t);
        Self::ALL.iter().copied().find(|v| is(v.name()) || v.aliases().iter().any(|a| is(a))).ok_or_else(|| {
            UnknownName {
                option: Self::SETTING.to_string(),
                given: s.to_string(),
                names: Self::ALL.iter().map(|v| v.name()).collect(),
            }
        })
    }
}

/// A name that is none of a setting's: the message lists the accepted names, under the
/// option name the front end gives ([`UnknownName::for_option`]).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct UnknownName {
    option: String,
    given: String,
    names: Vec<&'static str>,
}

impl UnknownName {
    /// The same error under a front end's name for the option (`--sampler`), which is what
    /// its user typed.
    pub fn for_option(mut self, option: &str) -> Self {
        self.option = option.to_string();
        self
    }

    /// The names accepted.
    pub fn names(&self) -> &[&'static str] {
        &self.names
    }
}

impl fmt::Display for UnknownName {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let list = match self.names.split_last() {
            Some((last, rest)) if !rest.is_empty() => format!("{} or {last}", rest.join(", ")),
            _ => self.names.join(", "),
        };
        write!(f, "{} must be {list}, got '{}'", self.option, self.given)
    }
}

impl std::error::Error for UnknownName {}

/// Implements [`Choice`] and `FromStr` for an enum from its values' names and help lines,
/// and `name` as an inherent method so callers need not import the trait:
///
/// ```ignore
/// crate::choice::named!(Isa, "isa", {
///     Scalar => "scalar", "no SIMD";
///     Sse => "sse" | "sse4", "SSE4.1";
/// });
/// ```
macro_rules! named {
    ($ty:ident, $setting:literal, { $($variant:ident => $name:literal $(| $alias:literal)*, $help:literal;)+ }) => {
        impl $ty {
            /// The value's name, as the command line, the Python package and the viewer
            /// spell it.
            pub fn name(self) -> &'static str {
                match self {
                    $($ty::$variant => $name,)+
                }
            }
        }

        impl $crate::choice::Choice for $ty {
            const SETTING: &'static str = $setting;
            const ALL: &'static [$ty] = &[$($ty::$variant),+];

            fn name(self) -> &'static str {
                $ty::name(self)
            }

            fn help(self) -> &'static str {
                match self {
                    $($ty::$variant => $help,)+
                }
            }

            fn aliases(self) -> &'static [&'static str] {
                match self {
                    $($ty::$variant => &[$($alias),*],)+
                }
            }
        }

        impl std::str::FromStr for $ty {
            type Err = $crate::choice::UnknownName;

            fn from_str(s: &str) -> Result<Self, Self::Err> {
                <$ty as $crate::choice::Choice>::from_name(s)
            }
        }
    };
}

pub(crate) use named;

#[cfg(test)]
mod tests {
    use super::*;

    #[derive(Clone, Copy, Debug, PartialEq, Eq)]
    enum Fruit {
        Apple,
        Pear,
        Plum,
    }

    named!(Fruit, "fruit", {
        Apple => "apple" | "pomme", "red or green";
        Pear => "pear", "soft";
        Plum => "plum", "purple";
    });

    #[test]
    fn names_parse_and_unknown_ones_list_the_accepted() {
        assert_eq!("pear".parse::<Fruit>(), Ok(Fruit::Pear));
        assert_eq!(" Plum ".parse::<Fruit>(), Ok(Fruit::Plum));
        assert_eq!("pomme".parse::<Fruit>(), Ok(Fruit::Apple));
        assert_eq!(Fruit::ALL.iter().map(|f| f.name()).collect::<Vec<_>>(), ["apple", "pear", "plum"]);
        let e = "kiwi".parse::<Fruit>().unwrap_err();
        assert_eq!(e.to_string(), "fruit must be apple, pear or plum, got 'kiwi'");
        assert_eq!(e.for_option("--fruit").to_string(), "--fruit must be apple, pear or plum, got 'kiwi'");
    }
}
