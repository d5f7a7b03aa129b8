//! Value types shared by the AbcCoreOgawa reader and writer: metadata strings, POD codes, time
//! samplings and the bit layout of property headers.
use std::collections::BTreeMap;

/// `key=value` pairs; serialized sorted by key, empty values dropped, joined with `;`.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct MetaData(BTreeMap<String, String>);

impl MetaData {
    pub fn new() -> Self {
        MetaData::default()
    }

    pub fn with(mut self, key: &str, value: &str) -> Self {
        self.set(key, value);
        self
    }

    pub fn set(&mut self, key: &str, value: &str) {
        self.0.insert(key.to_string(), value.to_string());
    }

    pub fn get(&self, key: &str) -> Option<&str> {
        self.0.get(key).map(String::as_str).filter(|v| !v.is_empty())
    }

    pub fn serialize(&self) -> String {
        let pairs: Vec<String> =
            self.0.iter().filter(|(_, v)| !v.is_empty()).map(|(k, v)| format!("{k}={v}")).collect();
        pairs.join(";")
    }

    /// Parses a serialized string; a repeated key keeps its first value.
    pub fn parse(text: &str) -> Self {
        let mut map = BTreeMap::new();
        for pair in text.split(';') {
            if let Some((key, value)) = pair.split_once('=') {
                map.entry(key.to_string()).or_insert_with(|| value.to_string());
            }
        }
        MetaData(map)
    }
}

/// Plain-old-data element types, with their on-disk codes.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Pod {
    Bool,
    U8,
    I8,
    U16,
    I16,
    U32,
    I32,
    U64,
    I64,
    F16,
    F32,
    F64,
    String,
    WString,
}

impl Pod {
    const ALL: [Pod; 14] = [
        Pod::Bool,
        Pod::U8,
        Pod::I8,
        Pod::U16,
        Pod::I16,
        Pod::U32,
        Pod::I32,
        Pod::U64,
        Pod::I64,
        Pod::F16,
        Pod::F32,
        Pod::F64,
        Pod::String,
        Pod::WString,
    ];

    pub fn code(self) -> u8 {
        Pod::ALL.iter().position(|&p| p == self).unwrap() as u8
    }

    pub fn from_code(code: u32) -> Option<Pod> {
        Pod::ALL.get(code as usize).copied()
    }

    /// Bytes per element; strings are variable (0 here).
    pub fn size(self) -> usize {
        match self {
            Pod::Bool | Pod::U8 | Pod::I8 => 1,
            Pod::U16 | Pod::I16 | Pod::F16 => 2,
            Pod::U32 | Pod::I32 | Pod::F32 => 4,
            Pod::U64 | Pod::I64 | Pod::F64 => 8,
            Pod::String | Pod::WString => 0,
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            Pod::Bool => "bool_t",
            Pod::U8 => "uint8_t",
            Pod::I8 => "int8_t",
            Pod::U16 => "uint16_t",
            Pod::I16 => "int16_t",
            Pod::U32 => "uint32_t",
            Pod::I32 => "int32_t",
            Pod::U64 => "uint64_t",
            Pod::I64 => "int64_t",
            Pod::F16 => "float16_t",
            Pod::F32 => "float32_t",
            Pod::F64 => "float64_t",
            Pod::String => "string",
            Pod::WString => "wstring",
        }
    }
}

/// `timePerCycle` that marks an acyclic sampling (every time stored).
pub const ACYCLIC_TIME_PER_CYCLE: f64 = f64::MAX / 32.0;

/// When samples happen: uniform (one stored time), cyclic (several) or acyclic (all of them).
#[derive(Clone, Debug, PartialEq)]
pub struct TimeSampling {
    pub time_per_cycle: f64,
    pub stored_times: Vec<f64>,
}

impl TimeSampling {
    pub fn identity() -> Self {
        TimeSampling { time_per_cycle: 1.0, stored_times: vec![0.0] }
    }

    /// Uniform sampling at `fps` frames per second, sample 0 at `start`.
    pub fn uniform(fps: f64, start: f64) -> Self {
        TimeSampling { time_per_cycle: 1.0 / fps, stored_times: vec![start] }
    }

    pub fn is_acyclic(&self) -> bool {
        self.time_per_cycle == ACYCLIC_TIME_PER_CYCLE
    }

    /// Time of sample `index` (an acyclic index past the stored times clamps to the last).
    pub fn sample_time(&self, index: u64) -> f64 {
        let n = self.stored_times.len().max(1) as u64;
        if self.is_acyclic() {
            return self.stored_times.get(index.min(n - 1) as usize).copied().unwrap_or(0.0);
        }
        let cycle = (index / n) as f64;
        self.stored_times.get((index % n) as usize).copied().unwrap_or(0.0) + cycle * self.time_per_cycle
    }

    /// The sample of `count` whose time is nearest to `time` (times increase with the index).
    pub fn nearest_index(&self, time: f64, count: u64) -> u64 {
        if count <= 1 {
            return 0;
        }
        let (mut lo, mut hi) = (0u64, count - 1);
        while lo < hi {
            let mid = lo + (hi - lo) / 2;
            if self.sample_time(mid) < time {
                lo = mid + 1;
            } else {
                hi = mid;
            }
        }
        if lo > 0 && (time - self.sample_time(lo - 1)).abs() <= (self.sample_time(lo) - time).abs() {
            lo - 1
        } else {
            lo
        }
    }
}

/// Kind of a property, as the low two bits of a header store it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PropertyKind {
    Compound,
    Scalar,
    Array,
}

/// Header bit fields (see the format note §3.4).
pub mod info {
    pub const KIND_MASK: u32 = 0x3;
    pub const HINT_SHIFT: u32 = 2;
    pub const POD_SHIFT: u32 = 4;
    pub const HAS_TIME_SAMPLING: u32 = 0x100;
    pub const EXPLICIT_CHANGES: u32 = 0x200;
    pub const HOMOGENEOUS: u32 = 0x400;
    pub const CONSTANT: u32 = 0x800;
    pub const EXTENT_SHIFT: u32 = 12;
    pub const METADATA_SHIFT: u32 = 20;
    /// Metadata index meaning "the string follows inline".
    pub const INLINE_METADATA: u8 = 0xFF;
}

/// Size hint for the variable-width integers of a header: 0 → u8, 1 → u16, 2 → u32.
pub fn size_hint(largest: u64) -> u32 {
    if largest <= 0xFF {
        0
    } else if largest <= 0xFFFF {
        1
    } else {
        2
    }
}

pub fn push_sized(out: &mut Vec<u8>, hint: u32, value: u32) {
    match hint {
        0 => out.push(value as u8),
        1 => out.extend_from_slice(&(value as u16).to_le_bytes()),
        _ => out.extend_from_slice(&value.to_le_bytes()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn metadata_sorts_keys_and_drops_empty_values() {
        let md = MetaData::new().with("interpretation", "point").with("geoScope", "vtx").with("notUV", "");
        assert_eq!(md.serialize(), "geoScope=vtx;interpretation=point");
        assert_eq!(
            MetaData::parse(&md.serialize()),
            MetaData::new().with("geoScope", "vtx").with("interpretation", "point")
        );
        assert_eq!(MetaData::parse("a=1;a=2").get("a"), Some("1"));
    }

    #[test]
    fn uniform_sampling_times_and_lookup() {
        let ts = TimeSampling::uniform(24.0, 1.0 / 24.0);
        assert!((ts.sample_time(23) - 1.0).abs() < 1e-12);
        assert_eq!(ts.nearest_index(0.5, 100), 11);
        assert_eq!(ts.nearest_index(100.0, 10), 9);
        let cyclic = TimeSampling { time_per_cycle: 1.0, stored_times: vec![0.0, 0.25] };
        assert_eq!(cyclic.sample_time(3), 1.25);
    }
}
