//! The one spelling table of each public enum that reaches a pipeline file, a CLI flag,
//! an artifact or a report: `Display` writes it, `FromStr` reads it back. Front ends
//! (serde in the driver, clap in the binaries) go through these, so a name cannot be
//! spelt two ways.

use std::fmt;
use std::str::FromStr;

use crate::{Metric, Placement, StopReason};

/// Writes and reads back a fixed name per variant.
macro_rules! spelling {
    ($ty:ty, $what:literal, [$($variant:path => $name:literal),+ $(,)?]) => {
        impl $ty {
            /// The canonical name (pipeline files, CLI, artifacts, reports).
            pub fn name(self) -> &'static str {
                match self {
                    $($variant => $name,)+
                }
            }
        }

        impl fmt::Display for $ty {
            fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                f.write_str(self.name())
            }
        }

        impl FromStr for $ty {
            type Err = String;

            fn from_str(s: &str) -> Result<Self, String> {
                $(if s == $name {
                    return Ok($variant);
                })+
                let names: Vec<String> = [$($name),+].iter().map(|n| format!("\"{n}\"")).collect();
                Err(format!(concat!($what, " '{}' is unknown: use {}"), s, names.join(" or ")))
            }
        }
    };
}

spelling!(Placement, "placement", [Placement::Optimal => "optimal", Placement::Subset => "subset"]);
spelling!(Metric, "metric", [Metric::Quadric => "quadric", Metric::LindstromTurk => "lindstrom-turk"]);
spelling!(StopReason, "stop reason", [
    StopReason::TargetReached => "target",
    StopReason::NoValidCollapse => "no-valid-collapse",
]);

#[cfg(test)]
mod tests {
    use super::*;

    /// Every name reads back as its variant, and a typo lists the valid names.
    #[test]
    fn names_round_trip_and_typos_list_the_choices() {
        for p in [Placement::Optimal, Placement::Subset] {
            assert_eq!(p.name().parse::<Placement>(), Ok(p));
        }
        for m in [Metric::Quadric, Metric::LindstromTurk] {
            assert_eq!(m.to_string().parse::<Metric>(), Ok(m));
        }
        for s in [StopReason::TargetReached, StopReason::NoValidCollapse] {
            assert_eq!(s.name().parse::<StopReason>(), Ok(s));
        }
        let err = "lindstrom".parse::<Metric>().unwrap_err();
        assert_eq!(err, "metric 'lindstrom' is unknown: use \"quadric\" or \"lindstrom-turk\"");
    }
}
