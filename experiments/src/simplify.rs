//! The names of meshoptimizer's simplification as a finish step ([`Simplify`]): parsed from the
//! command line and manifests, printed in the `simplify` column. Running it is
//! [`crate::finish`]'s.
//!
//! Names, the same on the command line, in manifests and in the `simplify` column:
//!
//! | name | budget |
//! | --- | --- |
//! | `none` | no simplification |
//! | `meshopt:rmt` | RMT's triangle count: integrated clustering on the body-centred lattice, same object, box, resolution and isovalue |
//! | `meshopt:0.25` | a ratio in (0, 1) of the method's own triangles |
//! | `meshopt:5000` | a triangle count (an integer >= 1) |
//! | `meshopt-locked:...` | the same with open borders locked |
//!
//! In a manifest the table form says the same: `{ method = "meshopt", target = "rmt" | 0.25 |
//! 5000, lock_border = false }`. Configuration ids get `_m<target>` (`_ml<target>` locked), then
//! `_vc` with the vertex-cache order.

use std::fmt;

use serde::de::{self, Deserializer, MapAccess, Visitor};
use serde::{Deserialize, Serialize};

/// The triangle budget of a simplification.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub enum SimplifyTarget {
    /// RMT's triangle count on the same object, box, resolution and isovalue.
    Rmt,
    /// A share in (0, 1) of the method's own triangles.
    Ratio(f64),
    /// A triangle count.
    Count(usize),
}

/// meshoptimizer's simplifier down to a budget, with or without locked borders.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Simplify {
    /// The budget.
    pub target: SimplifyTarget,
    /// Keep vertices on open borders (where the surface leaves the box) in place.
    pub lock_border: bool,
}

impl SimplifyTarget {
    /// The target as written after `meshopt:` (`rmt`, `0.25`, `5000`).
    pub fn label(self) -> String {
        match self {
            SimplifyTarget::Rmt => "rmt".into(),
            SimplifyTarget::Ratio(r) => r.to_string(),
            SimplifyTarget::Count(n) => n.to_string(),
        }
    }

    /// Parses `rmt`, a ratio in (0, 1) (written with a decimal point) or a count >= 1.
    pub fn parse(s: &str) -> Result<Self, String> {
        if s == "rmt" {
            return Ok(SimplifyTarget::Rmt);
        }
        if !s.contains(['.', 'e', 'E']) {
            if let Ok(n) = s.parse::<u64>() {
                return Self::count(n);
            }
        }
        match s.parse::<f64>() {
            Ok(r) => Self::ratio(r),
            Err(_) => Err(format!(
                "simplify target `{s}`: expected rmt, a ratio in (0, 1) or a triangle count"
            )),
        }
    }

    fn count(n: u64) -> Result<Self, String> {
        match usize::try_from(n) {
            Ok(n) if n >= 1 => Ok(SimplifyTarget::Count(n)),
            _ => Err(format!(
                "simplify target {n}: a triangle count must be at least 1"
            )),
        }
    }

    fn ratio(r: f64) -> Result<Self, String> {
        if r > 0.0 && r < 1.0 {
            Ok(SimplifyTarget::Ratio(r))
        } else {
            Err(format!(
                "simplify target {r}: a ratio must lie strictly between 0 and 1"
            ))
        }
    }
}

impl Simplify {
    /// The name (`meshopt:rmt`, `meshopt-locked:0.25`); see the [module documentation](self).
    pub fn name(&self) -> String {
        let method = if self.lock_border {
            "meshopt-locked"
        } else {
            "meshopt"
        };
        format!("{method}:{}", self.target.label())
    }

    /// The id suffix (`_mrmt`, `_ml0.25`).
    pub fn id_suffix(&self) -> String {
        let l = if self.lock_border { "l" } else { "" };
        format!("_m{l}{}", self.target.label())
    }

    /// Parses a name; `none` is `Ok(None)`.
    pub fn parse(s: &str) -> Result<Option<Self>, String> {
        if s == "none" {
            return Ok(None);
        }
        let (method, target) = s.split_once(':').ok_or_else(|| {
            format!(
                "unknown simplification `{s}` (expected none, meshopt:<target> or \
                 meshopt-locked:<target>, the target rmt, a ratio in (0, 1) or a triangle count)"
            )
        })?;
        let lock_border = match method {
            "meshopt" => false,
            "meshopt-locked" => true,
            other => {
                return Err(format!(
                    "unknown simplifier `{other}` (expected meshopt or meshopt-locked)"
                ))
            }
        };
        Ok(Some(Simplify {
            target: SimplifyTarget::parse(target)?,
            lock_border,
        }))
    }
}

/// The name of an optional simplification (`none` when absent).
pub fn simplify_name(s: Option<&Simplify>) -> String {
    s.map_or_else(|| "none".to_string(), Simplify::name)
}

/// A manifest's `simplify` value: `"none"`, a name, or the table form.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
#[serde(transparent)]
pub struct SimplifyChoice(pub Option<Simplify>);

impl SimplifyChoice {
    /// Parses a name ([`Simplify::parse`]).
    pub fn parse(s: &str) -> Result<Self, String> {
        Simplify::parse(s).map(SimplifyChoice)
    }
}

impl<'de> Deserialize<'de> for SimplifyChoice {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V;
        impl<'de> Visitor<'de> for V {
            type Value = SimplifyChoice;
            fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                f.write_str(
                    "\"none\", \"meshopt:<target>\" or { method = \"meshopt\", target = \"rmt\" \
                     | <ratio> | <count>, lock_border = <bool> }",
                )
            }
            fn visit_str<E: de::Error>(self, s: &str) -> Result<SimplifyChoice, E> {
                Simplify::parse(s).map(SimplifyChoice).map_err(E::custom)
            }
            fn visit_map<A: MapAccess<'de>>(self, mut map: A) -> Result<SimplifyChoice, A::Error> {
                let mut method: Option<String> = None;
                let mut target: Option<SimplifyTarget> = None;
                let mut lock_border = false;
                while let Some(key) = map.next_key::<String>()? {
                    match key.as_str() {
                        "method" => method = Some(map.next_value()?),
                        "target" => target = Some(map.next_value::<TargetValue>()?.0),
                        "lock_border" => lock_border = map.next_value()?,
                        other => {
                            return Err(de::Error::unknown_field(
                                other,
                                &["method", "target", "lock_border"],
                            ))
                        }
                    }
                }
                match method.as_deref() {
                    Some("meshopt") => {}
                    Some(other) => {
                        return Err(de::Error::custom(format!(
                            "unknown simplifier `{other}` (expected meshopt)"
                        )))
                    }
                    None => return Err(de::Error::missing_field("method")),
                }
                let target = target.ok_or_else(|| de::Error::missing_field("target"))?;
                Ok(SimplifyChoice(Some(Simplify {
                    target,
                    lock_border,
                })))
            }
        }
        d.deserialize_any(V)
    }
}

/// A `target` value: `"rmt"`, a float ratio or an integer count.
struct TargetValue(SimplifyTarget);

impl<'de> Deserialize<'de> for TargetValue {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V;
        impl Visitor<'_> for V {
            type Value = TargetValue;
            fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                f.write_str("\"rmt\", a ratio in (0, 1) or a triangle count")
            }
            fn visit_str<E: de::Error>(self, s: &str) -> Result<TargetValue, E> {
                if s == "rmt" {
                    Ok(TargetValue(SimplifyTarget::Rmt))
                } else {
                    Err(E::custom(format!(
                        "simplify target `{s}`: the only named target is rmt"
                    )))
                }
            }
            fn visit_i64<E: de::Error>(self, v: i64) -> Result<TargetValue, E> {
                let n = u64::try_from(v).map_err(|_| {
                    E::custom(format!(
                        "simplify target {v}: a triangle count must be at least 1"
                    ))
                })?;
                SimplifyTarget::count(n).map(TargetValue).map_err(E::custom)
            }
            fn visit_u64<E: de::Error>(self, v: u64) -> Result<TargetValue, E> {
                SimplifyTarget::count(v).map(TargetValue).map_err(E::custom)
            }
            fn visit_f64<E: de::Error>(self, v: f64) -> Result<TargetValue, E> {
                SimplifyTarget::ratio(v).map(TargetValue).map_err(E::custom)
            }
        }
        d.deserialize_any(V)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_parse_and_print_the_same() {
        for name in ["meshopt:rmt", "meshopt-locked:0.25", "meshopt:5000"] {
            let s = Simplify::parse(name).unwrap().unwrap();
            assert_eq!(s.name(), name);
        }
        assert_eq!(Simplify::parse("none"), Ok(None));
        let s = Simplify::parse("meshopt-locked:rmt").unwrap().unwrap();
        assert_eq!(s.id_suffix(), "_mlrmt");
        assert_eq!(
            Simplify::parse("meshopt:0.5").unwrap().unwrap().target,
            SimplifyTarget::Ratio(0.5)
        );
        assert_eq!(
            Simplify::parse("meshopt:12").unwrap().unwrap().target,
            SimplifyTarget::Count(12)
        );
    }

    #[test]
    fn bad_names_say_what_is_wrong() {
        assert!(Simplify::parse("qem")
            .unwrap_err()
            .contains("meshopt:<target>"));
        assert!(Simplify::parse("qem:rmt")
            .unwrap_err()
            .contains("unknown simplifier `qem`"));
        assert!(Simplify::parse("meshopt:1.5")
            .unwrap_err()
            .contains("between 0 and 1"));
        assert!(Simplify::parse("meshopt:0")
            .unwrap_err()
            .contains("at least 1"));
        assert!(Simplify::parse("meshopt:lots")
            .unwrap_err()
            .contains("`lots`"));
        assert!(Simplify::parse("meshopt:NaN")
            .unwrap_err()
            .contains("between 0 and 1"));
    }

    #[derive(Deserialize)]
    struct Doc {
        s: Vec<SimplifyChoice>,
    }

    #[test]
    fn manifest_values_take_names_and_tables() {
        let doc: Doc = toml::from_str(
            r#"s = ["none", "meshopt:0.5", { method = "meshopt", target = "rmt" },
                     { method = "meshopt", target = 0.25, lock_border = true },
                     { method = "meshopt", target = 4000 }]"#,
        )
        .unwrap();
        let names: Vec<String> = doc.s.iter().map(|c| simplify_name(c.0.as_ref())).collect();
        assert_eq!(
            names,
            [
                "none",
                "meshopt:0.5",
                "meshopt:rmt",
                "meshopt-locked:0.25",
                "meshopt:4000"
            ]
        );
        for (bad, says) in [
            (
                r#"s = [{ method = "qem", target = "rmt" }]"#,
                "unknown simplifier `qem`",
            ),
            (r#"s = [{ method = "meshopt" }]"#, "missing field `target`"),
            (
                r#"s = [{ method = "meshopt", target = 2.0 }]"#,
                "between 0 and 1",
            ),
            (r#"s = [{ method = "meshopt", target = -3 }]"#, "at least 1"),
            (
                r#"s = [{ method = "meshopt", target = "half" }]"#,
                "only named target is rmt",
            ),
            (
                r#"s = [{ method = "meshopt", target = "rmt", lock = true }]"#,
                "unknown field `lock`",
            ),
        ] {
            let e = toml::from_str::<Doc>(bad)
                .err()
                .map(|e| e.to_string())
                .unwrap_or_default();
            assert!(e.contains(says), "{bad}: {e}");
        }
    }
}
