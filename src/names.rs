//! The one spelling of every option value the front doors name in words: the command line's
//! values, Python's keyword values, reports and messages. A type of option values implements
//! [`OptionName`] once (its values, each one's name, the spellings it also accepts), and gets
//! `name()` and `FromStr` from it, so the CLI and Python parse and print the same words and an
//! error names the value as the caller spelled it, with the values there are.
//!
//! ```
//! use nbhd::{NonFinitePolicy, PivotPolicy};
//!
//! assert_eq!("sliding-midpoint".parse::<PivotPolicy>()?, PivotPolicy::SlidingMidpoint);
//! assert_eq!("sliding_midpoint".parse::<PivotPolicy>()?, PivotPolicy::SlidingMidpoint);
//! assert_eq!(NonFinitePolicy::Skip.name(), "skip");
//! let e = "drop".parse::<NonFinitePolicy>().unwrap_err();
//! assert_eq!(
//!     e.to_string(),
//!     "option non_finite: unknown non-finite policy \"drop\"; expected one of reject, skip"
//! );
//! # Ok::<(), nbhd::NbhdError>(())
//! ```

use crate::error::NbhdError;

/// A type of option values with one name each (see the module documentation).
pub trait OptionName: Copy + PartialEq + 'static {
    /// The option, as the error names it (`pivot`, `non_finite`).
    const OPTION: &'static str;
    /// What a value is, in words (`pivot`, `non-finite policy`).
    const WHAT: &'static str;
    /// Every value with its name, in the order a list of them shows.
    const NAMES: &'static [(Self, &'static str)];
    /// Other spellings also accepted (older names of the command line), each with its value.
    const ALIASES: &'static [(&'static str, Self)] = &[];

    /// The value's name.
    fn option_name(self) -> &'static str {
        Self::NAMES
            .iter()
            .find(|(v, _)| *v == self)
            .map_or("", |(_, n)| n)
    }
}

/// The value named `s` (case and `_` for `-` do not matter), or [`NbhdError::InvalidOption`]
/// naming the option, `s` as given, and every name.
pub fn parse_name<T: OptionName>(s: &str) -> Result<T, NbhdError> {
    let key = s.trim().to_ascii_lowercase().replace('_', "-");
    T::NAMES
        .iter()
        .map(|&(v, n)| (n, v))
        .chain(T::ALIASES.iter().copied())
        .find(|(n, _)| *n == key)
        .map(|(_, v)| v)
        .ok_or_else(|| NbhdError::InvalidOption {
            name: T::OPTION,
            reason: format!(
                "unknown {} {s:?}; expected one of {}",
                T::WHAT,
                T::NAMES
                    .iter()
                    .map(|(_, n)| *n)
                    .collect::<Vec<_>>()
                    .join(", ")
            ),
        })
}

/// Implements `name()` and `FromStr` for a type of option values from its [`OptionName`].
#[macro_export]
#[doc(hidden)]
macro_rules! named_option {
    ($ty:ty) => {
        impl $ty {
            /// The value's name: the one spelling of the command line, Python and reports
            /// (see `src/names.rs`).
            pub fn name(self) -> &'static str {
                <$ty as $crate::names::OptionName>::option_name(self)
            }
        }

        impl ::std::str::FromStr for $ty {
            type Err = $crate::error::NbhdError;
            fn from_str(s: &str) -> ::std::result::Result<Self, Self::Err> {
                $crate::names::parse_name(s)
            }
        }
    };
}
