//! The AbcCoreOgawa reader: turns the Ogawa tree into objects and properties with names,
//! metadata and samples. Every header, count and index is checked against the bytes actually
//! present; a group reached twice (a cycle or a shared subtree) is refused, and nesting is
//! bounded, so a hostile file cannot make it loop, recurse without end or allocate more than
//! the file holds.
use std::cell::RefCell;
use std::collections::HashSet;

use super::ogawa::{Child, Group, OgawaError, OgawaReader, OgawaResult};
use super::types::{info, MetaData, Pod, PropertyKind, TimeSampling};

/// Objects and compounds may nest this deep; real files use a handful of levels.
const MAX_DEPTH: usize = 128;
/// Only files written with Ogawa-Alembic file version 0 are known.
const FILE_VERSION: i32 = 0;

fn fail<T>(message: impl Into<String>) -> OgawaResult<T> {
    Err(OgawaError(message.into()))
}

/// An open archive: its tables and object tree (headers only; samples are read on demand).
pub struct Archive<'a> {
    pub ogawa: OgawaReader<'a>,
    pub metadata: MetaData,
    pub time_samplings: Vec<TimeSampling>,
    /// Largest sample count of each time sampling, as the file records it.
    pub max_samples: Vec<u32>,
    pub top: Object<'a>,
}

pub struct Object<'a> {
    pub name: String,
    pub full_name: String,
    pub metadata: MetaData,
    pub properties: Compound<'a>,
    pub children: Vec<Object<'a>>,
}

pub struct Compound<'a> {
    pub name: String,
    pub metadata: MetaData,
    pub members: Vec<Property<'a>>,
}

pub enum Property<'a> {
    Compound(Compound<'a>),
    Sampled(Sampled<'a>),
}

/// A scalar or array property: header fields plus the group holding its sample slots.
pub struct Sampled<'a> {
    pub name: String,
    pub metadata: MetaData,
    pub kind: PropertyKind,
    pub pod: Pod,
    pub extent: u8,
    pub num_samples: u32,
    pub first_changed: u32,
    pub last_changed: u32,
    pub time_sampling: u32,
    group: Group<'a>,
}

struct Builder<'a> {
    ogawa: OgawaReader<'a>,
    indexed: Vec<String>,
    time_sampling_count: usize,
    seen: RefCell<HashSet<u64>>,
}

impl<'a> Archive<'a> {
    pub fn open(bytes: &'a [u8]) -> OgawaResult<Self> {
        let ogawa = OgawaReader::new(bytes)?;
        let root = ogawa.root()?;
        if root.len() < 6 {
            return fail(format!("the archive root has {} children; Alembic needs 6", root.len()));
        }
        let version = read_i32(ogawa.child_data(&root, 0, "file version")?.bytes, "file version")?;
        if version != FILE_VERSION {
            return fail(format!("unsupported Alembic file version {version}"));
        }
        let library = read_i32(ogawa.child_data(&root, 1, "library version")?.bytes, "library version")?;
        if library < 9999 {
            return fail(format!("library version {library} is older than any Ogawa writer"));
        }
        let metadata = ogawa.child_data(&root, 3, "archive metadata")?;
        let metadata = MetaData::parse(&String::from_utf8_lossy(metadata.bytes));
        let (time_samplings, max_samples) =
            parse_time_samplings(ogawa.child_data(&root, 4, "time samplings")?.bytes)?;
        let indexed = parse_indexed_metadata(ogawa.child_data(&root, 5, "indexed metadata")?.bytes)?;
        let builder = Builder {
            ogawa,
            indexed,
            time_sampling_count: time_samplings.len(),
            seen: RefCell::new(HashSet::new()),
        };
        let top_group = ogawa.child_group(&root, 2, "top object")?;
        let top = builder.object(top_group, "ABC".into(), "/".into(), MetaData::new(), 0)?;
        Ok(Archive { ogawa, metadata, time_samplings, max_samples, top })
    }
}

impl<'a> Builder<'a> {
    /// Marks a group as visited; a second visit means a cycle or a shared subtree.
    fn visit(&self, group: &Group<'a>, depth: usize) -> OgawaResult<()> {
        if depth > MAX_DEPTH {
            return fail(format!("objects or properties nest deeper than {MAX_DEPTH} levels"));
        }
        if group.offset != 0 && !self.seen.borrow_mut().insert(group.offset) {
            return fail(format!("group at offset {} is reached twice (cyclic or shared)", group.offset));
        }
        Ok(())
    }

    fn object(
        &self,
        group: Group<'a>,
        name: String,
        full_name: String,
        metadata: MetaData,
        depth: usize,
    ) -> OgawaResult<Object<'a>> {
        self.visit(&group, depth)?;
        if group.len() < 2 {
            return fail(format!(
                "object {full_name}: its group has {} children, at least 2 expected",
                group.len()
            ));
        }
        let headers = self.ogawa.child_data(&group, group.len() - 1, &full_name)?.bytes;
        let headers = if headers.len() > 32 { &headers[..headers.len() - 32] } else { &[][..] };
        let child_headers = self.object_headers(headers, &full_name)?;
        if child_headers.len() != group.len() - 2 {
            return fail(format!(
                "object {full_name}: {} child headers for {} child groups",
                child_headers.len(),
                group.len() - 2
            ));
        }
        let properties_group = self.ogawa.child_group(&group, 0, &full_name)?;
        let properties =
            self.compound(properties_group, String::new(), MetaData::new(), &full_name, depth + 1)?;
        let mut children = Vec::with_capacity(child_headers.len());
        for (i, (child_name, child_metadata)) in child_headers.into_iter().enumerate() {
            let child_full =
                if full_name == "/" { format!("/{child_name}") } else { format!("{full_name}/{child_name}") };
            let child_group = self.ogawa.child_group(&group, i + 1, &child_full)?;
            children.push(self.object(child_group, child_name, child_full, child_metadata, depth + 1)?);
        }
        Ok(Object { name, full_name, metadata, properties, children })
    }

    fn object_headers(&self, mut bytes: &[u8], owner: &str) -> OgawaResult<Vec<(String, MetaData)>> {
        let mut out = Vec::new();
        while !bytes.is_empty() {
            let mut cursor = Cursor { bytes, owner };
            let len = cursor.sized(2)? as usize;
            let name = cursor.string(len)?;
            if name.is_empty() || name.contains('/') {
                return fail(format!("{owner}: child object name '{name}' is empty or contains '/'"));
            }
            if out.iter().any(|(n, _)| *n == name) {
                return fail(format!("{owner}: two child objects are named '{name}'"));
            }
            let index = cursor.take(1)?[0];
            let metadata = self.metadata(index, &mut cursor, 2)?;
            out.push((name, metadata));
            bytes = cursor.bytes;
        }
        Ok(out)
    }

    fn metadata(&self, index: u8, cursor: &mut Cursor<'_, '_>, hint: u32) -> OgawaResult<MetaData> {
        match index {
            0 => Ok(MetaData::new()),
            info::INLINE_METADATA => {
                let len = cursor.sized(hint)? as usize;
                Ok(MetaData::parse(&cursor.string(len)?))
            }
            i => match self.indexed.get(i as usize - 1) {
                Some(text) => Ok(MetaData::parse(text)),
                None => fail(format!(
                    "{}: metadata index {i} but the table has {} entries",
                    cursor.owner,
                    self.indexed.len()
                )),
            },
        }
    }

    fn compound(
        &self,
        group: Group<'a>,
        name: String,
        metadata: MetaData,
        owner: &str,
        depth: usize,
    ) -> OgawaResult<Compound<'a>> {
        self.visit(&group, depth)?;
        let mut members = Vec::new();
        if group.is_empty() {
            return Ok(Compound { name, metadata, members });
        }
        let path = if name.is_empty() { owner.to_string() } else { format!("{owner}/{name}") };
        let mut bytes = self.ogawa.child_data(&group, group.len() - 1, &path)?.bytes;
        let mut index = 0;
        while !bytes.is_empty() {
            if index + 1 >= group.len() {
                return fail(format!("{path}: more property headers than property groups"));
            }
            let mut cursor = Cursor { bytes, owner: &path };
            let word = u32::from_le_bytes(cursor.take(4)?.try_into().unwrap());
            let hint = (word >> info::HINT_SHIFT) & 0x3;
            let metadata_index = (word >> info::METADATA_SHIFT) as u8;
            let child_group = self.ogawa.child_group(&group, index, &path)?;
            let member = match word & info::KIND_MASK {
                0 => {
                    let len = cursor.sized(hint)? as usize;
                    let member_name = cursor.string(len)?;
                    let member_metadata = self.metadata(metadata_index, &mut cursor, hint)?;
                    Property::Compound(self.compound(
                        child_group,
                        member_name,
                        member_metadata,
                        &path,
                        depth + 1,
                    )?)
                }
                kind => {
                    self.visit(&child_group, depth + 1)?;
                    Property::Sampled(self.sampled(
                        word,
                        kind,
                        hint,
                        metadata_index,
                        &mut cursor,
                        child_group,
                    )?)
                }
            };
            bytes = cursor.bytes;
            members.push(member);
            index += 1;
        }
        if index + 1 != group.len() {
            return fail(format!("{path}: {index} property headers for {} property groups", group.len() - 1));
        }
        Ok(Compound { name, metadata, members })
    }

    fn sampled(
        &self,
        word: u32,
        kind: u32,
        hint: u32,
        metadata_index: u8,
        cursor: &mut Cursor<'_, '_>,
        group: Group<'a>,
    ) -> OgawaResult<Sampled<'a>> {
        let owner = cursor.owner.to_string();
        let pod_code = (word >> info::POD_SHIFT) & 0xF;
        let pod = Pod::from_code(pod_code)
            .ok_or_else(|| OgawaError(format!("{owner}: unknown POD code {pod_code}")))?;
        let extent = (word >> info::EXTENT_SHIFT) as u8;
        let num_samples = cursor.sized(hint)?;
        let (mut first_changed, mut last_changed) = (1, num_samples.saturating_sub(1));
        if word & info::EXPLICIT_CHANGES != 0 {
            first_changed = cursor.sized(hint)?;
            last_changed = cursor.sized(hint)?;
        }
        if word & info::CONSTANT != 0 {
            (first_changed, last_changed) = (0, 0);
        }
        let time_sampling = if word & info::HAS_TIME_SAMPLING != 0 { cursor.sized(hint)? } else { 0 };
        let len = cursor.sized(hint)? as usize;
        let name = cursor.string(len)?;
        let metadata = self.metadata(metadata_index, cursor, hint)?;
        let path = format!("{owner}/{name}");
        if extent == 0 {
            return fail(format!("{path}: extent 0"));
        }
        if time_sampling as usize >= self.time_sampling_count {
            return fail(format!("{path}: time sampling {time_sampling} does not exist"));
        }
        let explicit = word & info::EXPLICIT_CHANGES != 0 && word & info::CONSTANT == 0;
        if explicit && (first_changed > last_changed || last_changed >= num_samples) {
            return fail(format!("{path}: changed samples {first_changed}..{last_changed} of {num_samples}"));
        }
        let kind = if kind == 1 { PropertyKind::Scalar } else { PropertyKind::Array };
        Ok(Sampled {
            name: path,
            metadata,
            kind,
            pod,
            extent,
            num_samples,
            first_changed,
            last_changed,
            time_sampling,
            group,
        })
    }
}

impl<'a> Sampled<'a> {
    /// The short name (last path component).
    pub fn short_name(&self) -> &str {
        self.name.rsplit('/').next().unwrap_or(&self.name)
    }

    /// The stored slot that holds sample `index` (the reference library's mapping).
    fn slot(&self, index: u32) -> u32 {
        let (first, last) = (self.first_changed, self.last_changed);
        if first == 0 && last == 0 || index < first {
            0
        } else if index >= last {
            (last + 1).saturating_sub(first)
        } else {
            index - first + 1
        }
    }

    /// Whether the property stores no sample at all (Blender writes such properties for an
    /// object it leaves empty: a hair object without curves, or one mixing cyclic and non-cyclic
    /// curves).
    pub fn holds_no_sample(&self) -> bool {
        self.group.is_empty()
    }

    /// The sample bytes (key stripped) of sample `index`; an empty slice for an empty sample.
    pub fn sample_bytes(&self, ogawa: &OgawaReader<'a>, index: u32) -> OgawaResult<&'a [u8]> {
        if index >= self.num_samples.max(1) {
            return fail(format!("{}: sample {index} of {}", self.name, self.num_samples));
        }
        let slot = self.slot(index) as usize;
        let child = if self.kind == PropertyKind::Array { slot * 2 } else { slot };
        if self.holds_no_sample() {
            return fail(format!(
                "{}: the property holds no sample: its writer left the object empty",
                self.name
            ));
        }
        if child >= self.group.len() {
            return fail(format!(
                "{}: sample {index} needs slot {slot}, the property stores {}",
                self.name,
                self.group.len()
            ));
        }
        let bytes = match ogawa.child(&self.group, child)? {
            Child::Data(data) => data.bytes,
            Child::Group(_) => return fail(format!("{}: sample slot {slot} is a group", self.name)),
        };
        Ok(if bytes.len() < 16 { &[] } else { &bytes[16..] })
    }

    /// Checks the POD type and extent a caller expects.
    pub fn expect(&self, pods: &[Pod], extent: u8) -> OgawaResult<()> {
        if !pods.contains(&self.pod) || self.extent != extent {
            return fail(format!(
                "{} is {}×{}, expected {}×{extent}",
                self.name,
                self.pod.name(),
                self.extent,
                pods.iter().map(|p| p.name()).collect::<Vec<_>>().join(" or ")
            ));
        }
        Ok(())
    }

    /// Sample `index` as numbers converted to f64 (any numeric POD), with its element count.
    pub fn read_f64(&self, ogawa: &OgawaReader<'a>, index: u32) -> OgawaResult<Vec<f64>> {
        let bytes = self.sample_bytes(ogawa, index)?;
        let size = self.pod.size();
        if size == 0 {
            return fail(format!("{} holds strings, numbers expected", self.name));
        }
        let stride = size * self.extent as usize;
        if bytes.len() % stride != 0 {
            return fail(format!(
                "{}: {} bytes are not a whole number of {}×{} elements",
                self.name,
                bytes.len(),
                self.pod.name(),
                self.extent
            ));
        }
        Ok(bytes.chunks_exact(size).map(|b| pod_to_f64(self.pod, b)).collect())
    }

    /// Sample `index`'s bytes, when the property holds integers in whole elements.
    fn integer_bytes(&self, ogawa: &OgawaReader<'a>, index: u32) -> OgawaResult<&'a [u8]> {
        let bytes = self.sample_bytes(ogawa, index)?;
        let integer = matches!(
            self.pod,
            Pod::U8 | Pod::I8 | Pod::U16 | Pod::I16 | Pod::U32 | Pod::I32 | Pod::U64 | Pod::I64
        );
        if !integer || bytes.len() % (self.pod.size() * self.extent as usize) != 0 {
            return fail(format!(
                "{} is {}×{} ({} bytes), integers expected",
                self.name,
                self.pod.name(),
                self.extent,
                bytes.len()
            ));
        }
        Ok(bytes)
    }

    /// Sample `index` of an integer property as `u32` values, read as integers (no detour
    /// through floats: ids past 2^24 stay exact). A negative or too large value is an error
    /// naming its entry.
    pub fn read_u32(&self, ogawa: &OgawaReader<'a>, index: u32) -> OgawaResult<Vec<u32>> {
        let bytes = self.integer_bytes(ogawa, index)?;
        let size = self.pod.size();
        let in_range = |b: &[u8]| (0.0..=u32::MAX as f64).contains(&pod_to_f64(self.pod, b));
        let values: Vec<u32> = match self.pod {
            // A negative `i32` keeps its top bit set as `u32`: one test over the whole array.
            Pod::U32 | Pod::I32 => {
                bytes.chunks_exact(4).map(|b| u32::from_le_bytes(b.try_into().unwrap())).collect()
            }
            pod => bytes
                .chunks_exact(size)
                .map(|b| if in_range(b) { pod_to_f64(pod, b) as u32 } else { 0 })
                .collect(),
        };
        let negative = self.pod == Pod::I32 && values.iter().fold(0, |bits, &v| bits | v) & 0x8000_0000 != 0;
        if negative || !matches!(self.pod, Pod::U32 | Pod::I32) {
            if let Some(i) = bytes.chunks_exact(size).position(|b| !in_range(b)) {
                let value = pod_to_f64(self.pod, &bytes[i * size..(i + 1) * size]);
                return fail(format!("{}: entry {i} is {value}, not a count or index", self.name));
            }
        }
        Ok(values)
    }

    /// Sample `index` of an integer property as `i64` values, exactly (a `uint64`'s as its bits:
    /// see `AttributeKind::UInt64`).
    pub fn read_i64(&self, ogawa: &OgawaReader<'a>, index: u32) -> OgawaResult<Vec<i64>> {
        let bytes = self.integer_bytes(ogawa, index)?;
        let size = self.pod.size();
        let pod = self.pod;
        Ok(bytes
            .chunks_exact(size)
            .map(|b| match pod {
                Pod::U64 | Pod::I64 => i64::from_le_bytes(b.try_into().unwrap()),
                // The narrower integers are exact as f64.
                _ => pod_to_f64(pod, b) as i64,
            })
            .collect())
    }

    /// Sample `index` as f32 values (other numeric PODs are converted).
    pub fn read_f32(&self, ogawa: &OgawaReader<'a>, index: u32) -> OgawaResult<Vec<f32>> {
        let mut out = Vec::new();
        self.append_f32(ogawa, index, &mut out)?;
        Ok(out)
    }

    /// [`Self::read_f32`], appended to `out`.
    pub fn append_f32(&self, ogawa: &OgawaReader<'a>, index: u32, out: &mut Vec<f32>) -> OgawaResult<()> {
        if self.pod != Pod::F32 {
            out.extend(self.read_f64(ogawa, index)?.into_iter().map(|v| v as f32));
            return Ok(());
        }
        self.append_f32_as(ogawa, index, out)
    }

    /// Sample `index` of a float32 property as `T` (`f32`, `Vec3`, …) by one plain copy: the
    /// file is little-endian like the host, and the copy does not care that Ogawa blocks are
    /// packed without alignment.
    pub fn read_f32_as<T: bytemuck::Pod>(&self, ogawa: &OgawaReader<'a>, index: u32) -> OgawaResult<Vec<T>> {
        let mut out = Vec::new();
        self.append_f32_as(ogawa, index, &mut out)?;
        Ok(out)
    }

    /// [`Self::read_f32_as`], appended to `out` (a reader putting several objects' arrays one
    /// after another copies each once).
    pub fn append_f32_as<T: bytemuck::Pod>(
        &self,
        ogawa: &OgawaReader<'a>,
        index: u32,
        out: &mut Vec<T>,
    ) -> OgawaResult<()> {
        let bytes = self.sample_bytes(ogawa, index)?;
        let stride = 4 * self.extent as usize;
        if self.pod != Pod::F32 || std::mem::size_of::<T>() % 4 != 0 || stride % std::mem::size_of::<T>() != 0
        {
            return fail(format!(
                "{} is {}×{}, not float32 values of this size",
                self.name,
                self.pod.name(),
                self.extent
            ));
        }
        if bytes.len() % stride != 0 {
            return fail(format!(
                "{}: {} bytes are not a whole number of float32×{} elements",
                self.name,
                bytes.len(),
                self.extent
            ));
        }
        // One plain copy into the spare capacity (not zeroed first: the pages of a large
        // reserved array are touched once).
        let count = bytes.len() / std::mem::size_of::<T>();
        out.reserve(count);
        let spare = &mut out.spare_capacity_mut()[..count];
        // SAFETY: `spare` holds `count` elements of `T`, exactly `bytes.len()` bytes, and does
        // not overlap `bytes` (a borrow of the file); `T: Pod` takes any bytes, so the first
        // `count` spare elements are initialized by the copy before the length covers them.
        unsafe {
            std::ptr::copy_nonoverlapping(bytes.as_ptr(), spare.as_mut_ptr().cast::<u8>(), bytes.len());
            out.set_len(out.len() + count);
        }
        Ok(())
    }

    /// A string sample: NUL-terminated strings, concatenated.
    pub fn read_strings(&self, ogawa: &OgawaReader<'a>, index: u32) -> OgawaResult<Vec<String>> {
        if self.pod != Pod::String {
            return fail(format!("{} is {}, string expected", self.name, self.pod.name()));
        }
        let bytes = self.sample_bytes(ogawa, index)?;
        let bytes = bytes.strip_suffix(&[0]).unwrap_or(bytes);
        Ok(bytes.split(|&b| b == 0).map(|s| String::from_utf8_lossy(s).into_owned()).collect())
    }
}

/// One POD element (little-endian) as f64; `b` has exactly `pod.size()` bytes.
fn pod_to_f64(pod: Pod, b: &[u8]) -> f64 {
    match pod {
        Pod::Bool | Pod::U8 => b[0] as f64,
        Pod::I8 => b[0] as i8 as f64,
        Pod::U16 => u16::from_le_bytes([b[0], b[1]]) as f64,
        Pod::I16 => i16::from_le_bytes([b[0], b[1]]) as f64,
        Pod::U32 => u32::from_le_bytes(b.try_into().unwrap()) as f64,
        Pod::I32 => i32::from_le_bytes(b.try_into().unwrap()) as f64,
        Pod::U64 => u64::from_le_bytes(b.try_into().unwrap()) as f64,
        Pod::I64 => i64::from_le_bytes(b.try_into().unwrap()) as f64,
        Pod::F16 => f16_to_f64(u16::from_le_bytes([b[0], b[1]])),
        Pod::F32 => f32::from_le_bytes(b.try_into().unwrap()) as f64,
        Pod::F64 => f64::from_le_bytes(b.try_into().unwrap()),
        Pod::String | Pod::WString => 0.0,
    }
}

fn f16_to_f64(h: u16) -> f64 {
    let sign = if h & 0x8000 != 0 { -1.0 } else { 1.0 };
    let exponent = ((h >> 10) & 0x1F) as i32;
    let mantissa = (h & 0x3FF) as f64;
    sign * match exponent {
        0 => mantissa * 2f64.powi(-24),
        31 if mantissa == 0.0 => f64::INFINITY,
        31 => f64::NAN,
        e => (1.0 + mantissa / 1024.0) * 2f64.powi(e - 15),
    }
}

/// A bounds-checked reader over a header block.
struct Cursor<'b, 'o> {
    bytes: &'b [u8],
    owner: &'o str,
}

impl<'b> Cursor<'b, '_> {
    fn take(&mut self, n: usize) -> OgawaResult<&'b [u8]> {
        if n > self.bytes.len() {
            return fail(format!(
                "{}: header block ends early (needs {n} more bytes, has {})",
                self.owner,
                self.bytes.len()
            ));
        }
        let (head, rest) = self.bytes.split_at(n);
        self.bytes = rest;
        Ok(head)
    }

    fn sized(&mut self, hint: u32) -> OgawaResult<u32> {
        Ok(match hint {
            0 => self.take(1)?[0] as u32,
            1 => u16::from_le_bytes(self.take(2)?.try_into().unwrap()) as u32,
            _ => u32::from_le_bytes(self.take(4)?.try_into().unwrap()),
        })
    }

    fn string(&mut self, len: usize) -> OgawaResult<String> {
        Ok(String::from_utf8_lossy(self.take(len)?).into_owned())
    }
}

fn read_i32(bytes: &[u8], what: &str) -> OgawaResult<i32> {
    match bytes.try_into() {
        Ok(b) => Ok(i32::from_le_bytes(b)),
        Err(_) => fail(format!("{what} has {} bytes, 4 expected", bytes.len())),
    }
}

fn parse_time_samplings(mut bytes: &[u8]) -> OgawaResult<(Vec<TimeSampling>, Vec<u32>)> {
    let mut samplings = Vec::new();
    let mut max_samples = Vec::new();
    while !bytes.is_empty() {
        let mut cursor = Cursor { bytes, owner: "time samplings" };
        let max = u32::from_le_bytes(cursor.take(4)?.try_into().unwrap());
        let time_per_cycle = f64::from_le_bytes(cursor.take(8)?.try_into().unwrap());
        let count = u32::from_le_bytes(cursor.take(4)?.try_into().unwrap()) as usize;
        let times = cursor.take(count.saturating_mul(8))?;
        let stored_times: Vec<f64> =
            times.chunks_exact(8).map(|b| f64::from_le_bytes(b.try_into().unwrap())).collect();
        if stored_times.is_empty() || time_per_cycle.is_nan() || time_per_cycle <= 0.0 {
            return fail(format!("time sampling {} has no times or a non-positive cycle", samplings.len()));
        }
        samplings.push(TimeSampling { time_per_cycle, stored_times });
        max_samples.push(max);
        bytes = cursor.bytes;
    }
    if samplings.is_empty() {
        samplings.push(TimeSampling::identity());
        max_samples.push(0);
    }
    Ok((samplings, max_samples))
}

fn parse_indexed_metadata(mut bytes: &[u8]) -> OgawaResult<Vec<String>> {
    let mut entries = Vec::new();
    while !bytes.is_empty() {
        let mut cursor = Cursor { bytes, owner: "indexed metadata" };
        let len = cursor.take(1)?[0] as usize;
        entries.push(cursor.string(len)?);
        bytes = cursor.bytes;
    }
    Ok(entries)
}

impl<'a> Compound<'a> {
    pub fn get(&self, name: &str) -> Option<&Property<'a>> {
        self.members.iter().find(|m| m.name() == name)
    }

    pub fn compound(&self, name: &str) -> Option<&Compound<'a>> {
        match self.get(name)? {
            Property::Compound(c) => Some(c),
            Property::Sampled(_) => None,
        }
    }

    pub fn sampled(&self, name: &str) -> Option<&Sampled<'a>> {
        match self.get(name)? {
            Property::Sampled(s) => Some(s),
            Property::Compound(_) => None,
        }
    }
}

impl Property<'_> {
    pub fn name(&self) -> &str {
        match self {
            Property::Compound(c) => &c.name,
            Property::Sampled(s) => s.short_name(),
        }
    }
}
