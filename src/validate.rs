//! One validation layer for numbers that come from outside: recipes, manifests, command-line
//! flags and file headers. Every such number is checked here to be finite and inside a
//! documented range before anything uses it, and a refusal names the key, the value and the
//! range ("[water] r_max = -1 must be in (0, 0.5]"), so a farm log says what to fix.
//!
//! Callers add where the number came from (a recipe line, a flag); the check itself is shared.
use std::fmt;

use crate::error::{Error, Result};

/// An interval of accepted values; either end may be open or unbounded.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Range {
    min: f64,
    max: f64,
    min_open: bool,
    max_open: bool,
}

impl Range {
    /// `[min, max]`.
    pub const fn closed(min: f64, max: f64) -> Range {
        Range { min, max, min_open: false, max_open: false }
    }

    /// `(min, max]`: above `min`, at most `max`.
    pub const fn above(min: f64, max: f64) -> Range {
        Range { min, max, min_open: true, max_open: false }
    }

    /// `(min, max)`.
    pub const fn open(min: f64, max: f64) -> Range {
        Range { min, max, min_open: true, max_open: true }
    }

    /// `[min, max)`.
    pub const fn below(min: f64, max: f64) -> Range {
        Range { min, max, min_open: false, max_open: true }
    }

    pub fn contains(&self, value: f64) -> bool {
        // Most values were f32 (recipes, flags), and a closed end such as 0.1 or 1e-6 has no exact
        // f32: the f32 nearest to it is that end too.
        let nearest_f32 = |end: f64| end as f32 as f64;
        let low = if self.min_open { value > self.min } else { value >= self.min.min(nearest_f32(self.min)) };
        let high =
            if self.max_open { value < self.max } else { value <= self.max.max(nearest_f32(self.max)) };
        value.is_finite() && low && high
    }
}

/// Fractions and rates of a whole: `[0, 1]`.
pub const FRACTION: Range = Range::closed(0.0, 1.0);
/// Coordinates, metres: a groom, obstacle or light anywhere within a kilometre of the origin.
pub const COORDINATE: Range = Range::closed(-1e3, 1e3);
/// Young's and shear moduli, Pa: from soft rubber-like fibres (1e5) to diamond (1e12). Hair is
/// about 3.9e9; far below 1e5 a rod's bend–twist compliance overflows `f32`.
pub const MODULUS: Range = Range::closed(1e5, 1e12);
/// Material density, kg/m³: from foams (1) to above osmium (1e5); keratin is about 1300.
pub const DENSITY: Range = Range::closed(1.0, 1e5);
/// Simulated seconds a stage or a run may last (the step budget bounds the total work).
pub const SECONDS: Range = Range::closed(0.0, 1e5);
/// Time step, seconds: a microsecond to a tenth of a second (hair styling runs at 1/240–1/1440;
/// beyond 0.1 s a step outruns a strand's fall through its own segment length).
pub const TIME_STEP: Range = Range::closed(1e-6, 0.1);
/// Solver iterations per step.
pub const ITERATIONS: Range = Range::closed(1.0, 1000.0);
/// Metres per unit of a groom file (`--units`, a manifest's `units`, a USD layer's
/// `metersPerUnit`): a micrometre to a kilometre, which holds every length unit DCC tools write
/// (mm, cm, inch, foot, m). Outside it hair (strands of about 1 mm to 2 m) would span more than
/// 10^6 units or less than 10^-6 of one: at 1e-30 every strand collapses to a point, at 1e30 a
/// 1-unit strand reaches past any scene.
pub const UNITS: Range = Range::closed(1e-6, 1e3);
/// A frame number to read from an animated groom: negative frames are real (a simulation's
/// pre-roll); beyond a billion is a typo.
pub const FRAME: Range = Range::closed(-1e9, 1e9);

impl fmt::Display for Range {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let open = if self.min_open { '(' } else { '[' };
        let close = if self.max_open { ')' } else { ']' };
        write!(f, "{open}{}, {}{close}", shortest(self.min), shortest(self.max))
    }
}

/// A number as written: an `f32` widened to `f64` prints as the `f32` (0.001, not
/// 0.0010000000474974513), and from ten million up or below a ten-thousandth in exponent form
/// (1e30, 1e-9; not 31 digits or nine zeros).
pub fn shortest(value: f64) -> String {
    let narrow = value as f32;
    let large = value.abs() >= 1e7 || (value != 0.0 && value.abs() < 1e-4);
    match (narrow as f64 == value, large) {
        (true, false) => narrow.to_string(),
        (true, true) => format!("{narrow:e}"),
        (false, false) => value.to_string(),
        (false, true) => format!("{value:e}"),
    }
}

/// A duration summed from `f32` seconds, as a person wrote it: to the microsecond (stages of 0.2
/// and 1.5 s last 1.7 s, not 1.7000000476837158).
pub fn seconds_text(seconds: f64) -> String {
    shortest((seconds * 1e6).round() / 1e6)
}

/// Checks one number; the message names the key, the value and the range.
pub fn number(key: &str, value: impl Into<f64>, range: Range) -> std::result::Result<(), String> {
    let value = value.into();
    if range.contains(value) {
        Ok(())
    } else {
        Err(format!("{key} = {} must be a finite number in {range}", shortest(value)))
    }
}

/// A vector as written, each component as [`shortest`] writes it: `[1e30, 0, NaN]`.
pub fn vector_text(value: [f32; 3]) -> String {
    format!("[{}, {}, {}]", shortest(value[0].into()), shortest(value[1].into()), shortest(value[2].into()))
}

/// Checks every component of a vector against `range`.
pub fn vector(key: &str, value: [f32; 3], range: Range) -> std::result::Result<(), String> {
    match value.iter().position(|&c| !range.contains(c as f64)) {
        None => Ok(()),
        Some(_) => Err(format!("{key} = {} must have finite components in {range}", vector_text(value))),
    }
}

/// Checks a direction: finite components within `range` and not (nearly) zero length.
pub fn direction(key: &str, value: [f32; 3]) -> std::result::Result<(), String> {
    vector(key, value, Range::closed(-1e6, 1e6))?;
    let length = glam::Vec3::from(value).length();
    if length < 1e-6 {
        return Err(format!("{key} = {} is not a direction (zero length)", vector_text(value)));
    }
    Ok(())
}

/// [`number`] for a command-line flag: a usage error (exit code 2).
pub fn flag(key: &str, value: impl Into<f64>, range: Range) -> Result<()> {
    number(key, value, range).map_err(Error::Usage)
}

/// [`vector`] for a command-line flag.
pub fn flag_vector(key: &str, value: [f32; 3], range: Range) -> Result<()> {
    vector(key, value, range).map_err(Error::Usage)
}

/// [`direction`] for a command-line flag.
pub fn flag_direction(key: &str, value: [f32; 3]) -> Result<()> {
    direction(key, value).map_err(Error::Usage)
}

/// Reads a TOML array of exactly three numbers, as every vector of a recipe or shot is: toml's
/// own reading of a `[f32; 3]` in a plain table stops after the third element (`gravity = [0,
/// -9.8, 0, 5]` was read as [0, -9.8, 0], and three million elements were walked past unread).
pub fn three<'de, D: serde::Deserializer<'de>>(deserializer: D) -> std::result::Result<[f32; 3], D::Error> {
    struct Three;
    impl<'de> serde::de::Visitor<'de> for Three {
        type Value = [f32; 3];
        fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
            f.write_str("an array of 3 numbers")
        }
        fn visit_seq<A: serde::de::SeqAccess<'de>>(
            self,
            mut seq: A,
        ) -> std::result::Result<[f32; 3], A::Error> {
            let mut value = [0.0; 3];
            for (i, component) in value.iter_mut().enumerate() {
                *component = seq.next_element()?.ok_or_else(|| serde::de::Error::invalid_length(i, &self))?;
            }
            let mut length = 3;
            while seq.next_element::<serde::de::IgnoredAny>()?.is_some() {
                length += 1;
            }
            match length {
                3 => Ok(value),
                _ => Err(serde::de::Error::invalid_length(length, &self)),
            }
        }
    }
    deserializer.deserialize_seq(Three)
}

/// [`three`] for a vector that may be left out.
pub fn optional_three<'de, D: serde::Deserializer<'de>>(
    deserializer: D,
) -> std::result::Result<Option<[f32; 3]>, D::Error> {
    #[derive(serde::Deserialize)]
    struct Three(#[serde(deserialize_with = "three")] [f32; 3]);
    Ok(<Option<Three> as serde::Deserialize>::deserialize(deserializer)?.map(|Three(value)| value))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ranges_refuse_non_finite_and_respect_open_ends() {
        let positive = Range::above(0.0, 1.0);
        assert!(!positive.contains(0.0) && positive.contains(1.0) && !positive.contains(f64::NAN));
        assert!(!Range::below(0.0, 1.0).contains(1.0) && Range::below(0.0, 1.0).contains(0.0));
        assert!(!FRACTION.contains(f64::INFINITY) && !FRACTION.contains(-1e-9));
        // The ends as f32 values reach them (0.1f32 is above 0.1, 1e-6f32 below 1e-6); the next
        // f32 beyond does not.
        for end in [0.1f32, 1e-6] {
            assert!(TIME_STEP.contains(end.into()), "{end}");
        }
        assert!(!TIME_STEP.contains(f32::from_bits(0.1f32.to_bits() + 1).into()));
        assert!(!TIME_STEP.contains(f32::from_bits(1e-6f32.to_bits() - 1).into()));
    }

    #[test]
    fn refusals_name_key_value_and_range() {
        let e = number("[water] r_max", -1.0, Range::above(0.0, 0.5)).unwrap_err();
        assert!(e.contains("[water] r_max") && e.contains("-1") && e.contains("(0, 0.5]"), "{e}");
        let e = number("--exposure", f32::NAN, Range::closed(-30.0, 30.0)).unwrap_err();
        assert!(e.contains("NaN") && e.contains("[-30, 30]"), "{e}");
        assert!(direction("normal", [0.0; 3]).unwrap_err().contains("zero length"));
        assert!(vector("center", [0.0, f32::INFINITY, 0.0], COORDINATE).unwrap_err().contains("inf"));
        // Large values in exponent form, as written, not 31 digits.
        let e = number("--damping", 1e30f32, Range::closed(0.0, 1e4)).unwrap_err();
        assert!(e.contains("--damping = 1e30 must") && e.contains("[0, 10000]"), "{e}");
        assert!(FRAME.to_string() == "[-1e9, 1e9]" && MODULUS.to_string() == "[100000, 1e12]");
        assert_eq!(shortest(0.001f32.into()), "0.001");
        assert_eq!((shortest(1e-6f32.into()), shortest(8e-8)), ("1e-6".into(), "8e-8".into()));
    }
}
