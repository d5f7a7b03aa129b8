//! USD's integer and flag scalar types (`bool`, `uchar`, `int`, `uint`, `int64`, `uint64`) and
//! how a `.usda` value of each is read, as pxr reads it: an integer in the type's range; a number
//! with a fraction or exponent truncated toward zero, then in range (`int x = 2.9` is 2,
//! `uchar x = -0.5` is 0, `uchar x = -1.5` and `int x = 1e10` refuse the layer); no `inf` or
//! `nan`, and `true`/`false` only for a `bool`, which takes any number (non-zero is true).

/// A USD integer or flag type.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum IntType {
    Bool,
    UChar,
    Int,
    UInt,
    Int64,
    /// Held as the bits of an `i64` (see `AttributeKind::UInt64`).
    UInt64,
}

impl IntType {
    /// The type of a USD scalar type name (a tuple's base: `int` of `int3`).
    pub fn of(base: &str) -> Option<IntType> {
        Some(match base {
            "bool" => IntType::Bool,
            "uchar" => IntType::UChar,
            "int" => IntType::Int,
            "uint" => IntType::UInt,
            "int64" => IntType::Int64,
            "uint64" => IntType::UInt64,
            _ => return None,
        })
    }

    pub fn name(self) -> &'static str {
        match self {
            IntType::Bool => "bool",
            IntType::UChar => "uchar",
            IntType::Int => "int",
            IntType::UInt => "uint",
            IntType::Int64 => "int64",
            IntType::UInt64 => "uint64",
        }
    }

    /// The type as a number, for the bulk reader's per-type parsers (`bulk::Integer`).
    pub const fn code(self) -> u8 {
        self as u8
    }

    pub fn from_code(code: u8) -> IntType {
        const ALL: [IntType; 6] =
            [IntType::Bool, IntType::UChar, IntType::Int, IntType::UInt, IntType::Int64, IntType::UInt64];
        ALL[usize::from(code)]
    }

    /// A plain integer as this type's value, if it is one ([`read`](Self::read)'s fast path).
    pub fn take(self, value: i64) -> Option<i64> {
        if self == IntType::Bool {
            return Some(i64::from(value != 0));
        }
        let (min, max) = self.range();
        (min..=max).contains(&i128::from(value)).then_some(value)
    }

    /// The smallest and largest value.
    fn range(self) -> (i128, i128) {
        match self {
            IntType::Bool => (0, 1),
            IntType::UChar => (0, u8::MAX.into()),
            IntType::Int => (i32::MIN.into(), i32::MAX.into()),
            IntType::UInt => (0, u32::MAX.into()),
            IntType::Int64 => (i64::MIN.into(), i64::MAX.into()),
            IntType::UInt64 => (0, u64::MAX.into()),
        }
    }

    /// A finite double as this type's value, truncated toward zero as pxr reads a fraction, if
    /// in range (not for `bool`, which takes any number).
    /// (A `uint64` as its bits.)
    pub fn truncated(self, number: f64) -> Option<i64> {
        self.truncated_wide(number).map(|value| value as i64)
    }

    fn truncated_wide(self, number: f64) -> Option<i128> {
        let (min, max) = self.range();
        // `max + 1` is a power of two, exact as a double where `max` may not be.
        let truncated = number.trunc();
        (truncated >= min as f64 && truncated < (max + 1) as f64).then_some(truncated as i128)
    }

    /// A number token as this type's value (a `uint64` as its bits), or why it is not one.
    pub fn read(self, token: &str) -> Result<i64, String> {
        let bad = || format!("bad {} '{token}'", self.name());
        // A sign is pxr's only prefix (`+5` is a syntax error there).
        if token.starts_with('+') {
            return Err(bad());
        }
        if self == IntType::Bool {
            return match token {
                "true" => Ok(1),
                "false" => Ok(0),
                _ => super::lexer::parse_f64(token).map(|v| i64::from(v != 0.0)).ok_or_else(bad),
            };
        }
        let (min, max) = self.range();
        let value = match token.parse::<i128>() {
            Ok(value) => Some(value),
            // A fraction, an exponent or too many digits: read as a double, truncated.
            Err(_) => {
                let number = super::lexer::parse_f64(token).filter(|v| v.is_finite()).ok_or_else(bad)?;
                self.truncated_wide(number)
            }
        };
        match value {
            // The low 64 bits: a `uint64` past `i64::MAX` as its bits.
            Some(value) if (min..=max).contains(&value) => Ok(value as i64),
            _ => Err(format!("{} value '{token}' is out of its range, {min} to {max}", self.name())),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// What pxr 26 (usd-core) reads for each `primvars:foo = TOKEN` of each type, or refuses.
    #[test]
    fn values_read_as_pxr_reads_them() {
        let cases: &[(IntType, &str, Option<i64>)] = &[
            (IntType::UChar, "255", Some(255)),
            (IntType::UChar, "256", None),
            (IntType::UChar, "-1", None),
            (IntType::UChar, "-0", Some(0)),
            (IntType::UChar, "1.5", Some(1)),
            (IntType::UChar, "-0.5", Some(0)),
            (IntType::UChar, "-1.5", None),
            (IntType::UChar, "true", None),
            (IntType::Int, "2147483647", Some(i32::MAX.into())),
            (IntType::Int, "2147483648", None),
            (IntType::Int, "-2147483648", Some(i32::MIN.into())),
            (IntType::Int, "-2147483649", None),
            (IntType::Int, "2.9", Some(2)),
            (IntType::Int, "-1.5", Some(-1)),
            (IntType::Int, "1e3", Some(1000)),
            (IntType::Int, "1e10", None),
            (IntType::Int, "007", Some(7)),
            (IntType::Int, "nan", None),
            (IntType::Int, "inf", None),
            (IntType::Int, "+5", None),
            (IntType::UInt, "4294967295", Some(u32::MAX.into())),
            (IntType::UInt, "4294967295.5", Some(u32::MAX.into())),
            (IntType::UInt, "4294967296", None),
            (IntType::UInt, "-1", None),
            (IntType::Int64, "9223372036854775807", Some(i64::MAX)),
            (IntType::Int64, "9223372036854775808", None),
            (IntType::Int64, "1e10", Some(10_000_000_000)),
            (IntType::Int64, "1e19", None),
            (IntType::UInt64, "18446744073709551615", Some(-1)),
            (IntType::UInt64, "18446744073709551616", None),
            (IntType::UInt64, "1e19", Some(10_000_000_000_000_000_000u64 as i64)),
            (IntType::UInt64, "-1", None),
            (IntType::Bool, "2", Some(1)),
            (IntType::Bool, "-1", Some(1)),
            (IntType::Bool, "0", Some(0)),
            (IntType::Bool, "-0.5", Some(1)),
            (IntType::Bool, "nan", Some(1)),
            (IntType::Bool, "1e19", Some(1)),
            (IntType::Bool, "true", Some(1)),
            (IntType::Bool, "false", Some(0)),
        ];
        for &(int_type, token, expected) in cases {
            let read = int_type.read(token);
            assert_eq!(read.as_ref().ok().copied(), expected, "{int_type:?} '{token}': {read:?}");
            if let Err(message) = read {
                assert!(message.contains(&format!("'{token}'")), "{message}");
            }
        }
    }
}
