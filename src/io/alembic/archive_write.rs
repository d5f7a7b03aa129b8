//! The AbcCoreOgawa writer: objects, compound / scalar / array properties, time samplings and
//! metadata on top of the Ogawa container, laid out the way the reference C++ library lays
//! them out (so a file is byte-identical to its output for the same calls).
//!
//! Samples stream to disk as they are set; only the tree (names, metadata, per-sample child
//! references) stays in memory until `finish` writes the groups bottom-up.
use std::collections::HashMap;
use std::io::{self, Seek, Write};

use super::murmur3::sample_key;
use super::ogawa::{ChildRef, OgawaWriter};
use super::spooky::{chain_digests, hash_bytes, spooky128, Hash128, Spooky};
use super::types::{info, push_sized, size_hint, MetaData, Pod, TimeSampling};

/// `major * 10000 + minor * 100 + patch` of the Alembic library whose layout this follows.
pub const LIBRARY_VERSION: i32 = 10812;

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ObjectId(usize);
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct CompoundId(usize);
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PropertyId(usize);

struct ObjectNode {
    name: String,
    metadata: MetaData,
    children: Vec<ObjectId>,
    properties: CompoundId,
}

enum Member {
    Compound(CompoundId),
    Sampled(PropertyId),
}

struct CompoundNode {
    name: String,
    metadata: MetaData,
    members: Vec<Member>,
}

struct PropertyNode {
    name: String,
    metadata: MetaData,
    pod: Pod,
    extent: u8,
    is_array: bool,
    time_sampling: u32,
    num_samples: u32,
    first_changed: u32,
    last_changed: u32,
    /// Child references of the property group: one per stored slot (two for arrays).
    slots: Vec<ChildRef>,
    last_sample: Option<(usize, [u8; 16], ChildRef)>,
    every_sample_single: bool,
    /// Running Spooky chain of per-sample digests.
    chain: Option<Hash128>,
}

/// Writes an Alembic archive through an Ogawa stream.
pub struct ArchiveWriter<W: Write + Seek> {
    ogawa: OgawaWriter<W>,
    version_refs: [ChildRef; 2],
    dedup: HashMap<(usize, [u8; 16]), ChildRef>,
    objects: Vec<ObjectNode>,
    compounds: Vec<CompoundNode>,
    properties: Vec<PropertyNode>,
    time_samplings: Vec<TimeSampling>,
    archive_metadata: MetaData,
    indexed_metadata: Vec<String>,
}

impl<W: Write + Seek> ArchiveWriter<W> {
    pub fn new(out: W, archive_metadata: MetaData) -> io::Result<Self> {
        let mut ogawa = OgawaWriter::new(out)?;
        let file_version = ogawa.write_data(&[&0i32.to_le_bytes()])?;
        let library_version = ogawa.write_data(&[&LIBRARY_VERSION.to_le_bytes()])?;
        let mut writer = ArchiveWriter {
            ogawa,
            version_refs: [file_version, library_version],
            dedup: HashMap::new(),
            objects: Vec::new(),
            compounds: Vec::new(),
            properties: Vec::new(),
            time_samplings: vec![TimeSampling::identity()],
            archive_metadata,
            indexed_metadata: Vec::new(),
        };
        let properties = writer.new_compound(String::new(), MetaData::new());
        writer.objects.push(ObjectNode {
            name: "ABC".into(),
            metadata: MetaData::new(),
            children: Vec::new(),
            properties,
        });
        Ok(writer)
    }

    /// The unnamed top object ("/").
    pub fn top(&self) -> ObjectId {
        ObjectId(0)
    }

    /// Adds a time sampling (an equal one is reused) and returns its index.
    pub fn add_time_sampling(&mut self, sampling: TimeSampling) -> u32 {
        let equal = |a: &TimeSampling| {
            (a.time_per_cycle - sampling.time_per_cycle).abs() < 1e-9
                && a.stored_times.len() == sampling.stored_times.len()
                && a.stored_times.iter().zip(&sampling.stored_times).all(|(x, y)| (x - y).abs() < 1e-9)
        };
        if let Some(index) = self.time_samplings.iter().position(equal) {
            return index as u32;
        }
        self.time_samplings.push(sampling);
        (self.time_samplings.len() - 1) as u32
    }

    pub fn add_object(&mut self, parent: ObjectId, name: &str, metadata: MetaData) -> ObjectId {
        let properties = self.new_compound(String::new(), MetaData::new());
        let id = ObjectId(self.objects.len());
        self.objects.push(ObjectNode { name: name.into(), metadata, children: Vec::new(), properties });
        self.objects[parent.0].children.push(id);
        id
    }

    /// An object's top compound, which holds its properties.
    pub fn properties(&self, object: ObjectId) -> CompoundId {
        self.objects[object.0].properties
    }

    pub fn add_compound(&mut self, parent: CompoundId, name: &str, metadata: MetaData) -> CompoundId {
        let id = self.new_compound(name.into(), metadata);
        self.compounds[parent.0].members.push(Member::Compound(id));
        id
    }

    pub fn add_scalar(
        &mut self,
        parent: CompoundId,
        name: &str,
        metadata: MetaData,
        pod: Pod,
        extent: u8,
        time_sampling: u32,
    ) -> PropertyId {
        self.add_sampled(parent, name, metadata, pod, extent, time_sampling, false)
    }

    pub fn add_array(
        &mut self,
        parent: CompoundId,
        name: &str,
        metadata: MetaData,
        pod: Pod,
        extent: u8,
        time_sampling: u32,
    ) -> PropertyId {
        self.add_sampled(parent, name, metadata, pod, extent, time_sampling, true)
    }

    #[allow(clippy::too_many_arguments)]
    fn add_sampled(
        &mut self,
        parent: CompoundId,
        name: &str,
        metadata: MetaData,
        pod: Pod,
        extent: u8,
        time_sampling: u32,
        is_array: bool,
    ) -> PropertyId {
        let id = PropertyId(self.properties.len());
        self.properties.push(PropertyNode {
            name: name.into(),
            metadata,
            pod,
            extent,
            is_array,
            time_sampling,
            num_samples: 0,
            first_changed: 0,
            last_changed: 0,
            slots: Vec::new(),
            last_sample: None,
            every_sample_single: true,
            chain: None,
        });
        self.compounds[parent.0].members.push(Member::Sampled(id));
        id
    }

    fn new_compound(&mut self, name: String, metadata: MetaData) -> CompoundId {
        self.compounds.push(CompoundNode { name, metadata, members: Vec::new() });
        CompoundId(self.compounds.len() - 1)
    }

    /// Sets the next sample of a property: `bytes` are the little-endian PODs (strings: each
    /// followed by a NUL) and `elements` their count (1 for a scalar). A repeat of the previous
    /// sample is only counted; bytes already written anywhere in the archive are referenced, not
    /// written again.
    pub fn set_sample(&mut self, id: PropertyId, bytes: &[u8], elements: u64) -> io::Result<()> {
        self.set_sample_keyed(id, bytes, elements, sample_key(bytes))
    }

    /// [`ArchiveWriter::set_sample`] with the key already computed (`sample_key(bytes)`), so
    /// callers can hash several samples in parallel.
    pub fn set_sample_keyed(
        &mut self,
        id: PropertyId,
        bytes: &[u8],
        elements: u64,
        key: [u8; 16],
    ) -> io::Result<()> {
        let key = if bytes.is_empty() { [0u8; 16] } else { key };
        let node = &mut self.properties[id.0];
        let index = node.num_samples;
        node.num_samples += 1;
        node.every_sample_single &= elements == 1;
        let key_hash = (
            u64::from_le_bytes(key[..8].try_into().unwrap()),
            u64::from_le_bytes(key[8..].try_into().unwrap()),
        );
        let digest = if node.is_array {
            let mut dims = Vec::with_capacity(24);
            dims.extend_from_slice(&elements.to_le_bytes());
            dims.extend_from_slice(&key);
            spooky128(&dims)
        } else {
            key_hash
        };
        node.chain = Some(match node.chain {
            None => digest,
            Some(chain) => chain_digests(chain, digest),
        });
        if let Some((len, last_key, last_ref)) = node.last_sample {
            if len == bytes.len() && last_key == key {
                return Ok(()); // a repeat: counted, not stored
            }
            if node.first_changed == 0 {
                node.first_changed = index;
            } else {
                // Slots for the repeats since the last change point at the last stored sample.
                for _ in node.last_changed + 1..index {
                    push_slot(node, last_ref);
                }
            }
            node.last_changed = index;
        }
        let reference = match self.dedup.get(&(bytes.len(), key)) {
            Some(&reference) => reference,
            None if bytes.is_empty() => ChildRef::EMPTY_DATA,
            None => {
                let reference = self.ogawa.write_data(&[&key, bytes])?;
                self.dedup.insert((bytes.len(), key), reference);
                reference
            }
        };
        let node = &mut self.properties[id.0];
        node.last_sample = Some((bytes.len(), key, reference));
        push_slot(node, reference);
        Ok(())
    }

    /// Writes every group, the tables and the root, patches the header and returns the stream.
    pub fn finish(mut self) -> io::Result<W> {
        let (top_group, _) = self.write_object(ObjectId(0))?;
        let archive_metadata = self.archive_metadata.serialize();
        let archive_metadata = self.ogawa.write_data(&[archive_metadata.as_bytes()])?;
        let time_samplings = self.time_sampling_table();
        let time_samplings = self.ogawa.write_data(&[&time_samplings])?;
        let mut table = Vec::new();
        for entry in &self.indexed_metadata {
            table.push(entry.len() as u8);
            table.extend_from_slice(entry.as_bytes());
        }
        let indexed = self.ogawa.write_data(&[&table])?;
        let [file_version, library_version] = self.version_refs;
        let root = self.ogawa.write_group(&[
            file_version,
            library_version,
            top_group,
            archive_metadata,
            time_samplings,
            indexed,
        ])?;
        self.ogawa.finish(root)
    }

    fn time_sampling_table(&self) -> Vec<u8> {
        let mut max_samples = vec![0u32; self.time_samplings.len()];
        for p in &self.properties {
            let slot = &mut max_samples[p.time_sampling as usize];
            *slot = (*slot).max(p.num_samples);
        }
        let mut out = Vec::new();
        for (sampling, max) in self.time_samplings.iter().zip(max_samples) {
            out.extend_from_slice(&max.to_le_bytes());
            out.extend_from_slice(&sampling.time_per_cycle.to_le_bytes());
            out.extend_from_slice(&(sampling.stored_times.len() as u32).to_le_bytes());
            for t in &sampling.stored_times {
                out.extend_from_slice(&t.to_le_bytes());
            }
        }
        out
    }

    /// Writes an object's subtree; returns its group and its object hash (for the parent).
    fn write_object(&mut self, id: ObjectId) -> io::Result<(ChildRef, Hash128)> {
        let children = self.objects[id.0].children.clone();
        let mut child_groups = Vec::with_capacity(children.len());
        let mut hasher = Spooky::new();
        for &child in &children {
            let (group, hash) = self.write_object(child)?;
            child_groups.push(group);
            hasher.update(&hash_bytes(hash));
        }
        let top = self.objects[id.0].properties;
        let (member_refs, member_hashes) = self.write_members(top)?;
        let mut properties_hasher = Spooky::new();
        member_hashes.iter().for_each(|h| properties_hasher.update(&hash_bytes(*h)));
        let properties_hash = properties_hasher.finish();
        let children_hash = if children.is_empty() { (0, 0) } else { hasher.finish() };

        let mut headers = Vec::new();
        for &child in &children {
            let (name, metadata) =
                (self.objects[child.0].name.clone(), self.objects[child.0].metadata.serialize());
            headers.extend_from_slice(&(name.len() as u32).to_le_bytes());
            headers.extend_from_slice(name.as_bytes());
            let index = self.metadata_index(&metadata);
            headers.push(index);
            if index == info::INLINE_METADATA {
                headers.extend_from_slice(&(metadata.len() as u32).to_le_bytes());
                headers.extend_from_slice(metadata.as_bytes());
            }
        }
        headers.extend_from_slice(&hash_bytes(properties_hash));
        headers.extend_from_slice(&hash_bytes(children_hash));
        let headers_ref = self.ogawa.write_data(&[&headers])?;
        let top_ref = self.write_compound_group(top, member_refs)?;

        let mut group = Vec::with_capacity(children.len() + 2);
        group.push(top_ref);
        group.extend(child_groups);
        group.push(headers_ref);
        let group_ref = self.ogawa.write_group(&group)?;

        hasher.update(&hash_bytes(properties_hash));
        let node = &self.objects[id.0];
        let metadata = node.metadata.serialize();
        if !metadata.is_empty() {
            hasher.update(metadata.as_bytes());
        }
        hasher.update(node.name.as_bytes());
        Ok((group_ref, hasher.finish()))
    }

    /// Writes the groups of a compound's members; returns their references and hashes.
    fn write_members(&mut self, id: CompoundId) -> io::Result<(Vec<ChildRef>, Vec<Hash128>)> {
        let count = self.compounds[id.0].members.len();
        let mut refs = Vec::with_capacity(count);
        let mut hashes = Vec::with_capacity(count);
        for i in 0..count {
            let (reference, hash) = match self.compounds[id.0].members[i] {
                Member::Compound(child) => self.write_compound(child)?,
                Member::Sampled(property) => self.write_property(property)?,
            };
            refs.push(reference);
            hashes.push(hash);
        }
        Ok((refs, hashes))
    }

    /// A (non-top) compound: its members, its header block, its group; plus its hash.
    fn write_compound(&mut self, id: CompoundId) -> io::Result<(ChildRef, Hash128)> {
        let (refs, hashes) = self.write_members(id)?;
        let group = self.write_compound_group(id, refs)?;
        let node = &self.compounds[id.0];
        let mut hasher = Spooky::new();
        hashes.iter().for_each(|h| hasher.update(&hash_bytes(*h)));
        hasher.update(node.name.as_bytes());
        hasher.update(node.metadata.serialize().as_bytes());
        Ok((group, hasher.finish()))
    }

    /// The header block of a compound's members, then the compound's group.
    fn write_compound_group(&mut self, id: CompoundId, mut refs: Vec<ChildRef>) -> io::Result<ChildRef> {
        if refs.is_empty() {
            return Ok(ChildRef::EMPTY_GROUP);
        }
        let mut headers = Vec::new();
        for i in 0..self.compounds[id.0].members.len() {
            match self.compounds[id.0].members[i] {
                Member::Compound(child) => self.compound_header(child, &mut headers),
                Member::Sampled(property) => self.property_header(property, &mut headers),
            }
        }
        refs.push(self.ogawa.write_data(&[&headers])?);
        self.ogawa.write_group(&refs)
    }

    fn write_property(&mut self, id: PropertyId) -> io::Result<(ChildRef, Hash128)> {
        let group = self.ogawa.write_group(&self.properties[id.0].slots)?;
        let node = &self.properties[id.0];
        let sampling = &self.time_samplings[node.time_sampling as usize];
        let mut hasher = Spooky::new();
        hasher.update(node.name.as_bytes());
        hasher.update(node.metadata.serialize().as_bytes());
        hasher.update(&[node.pod.code(), node.extent]);
        if !node.is_array {
            hasher.update(&[0]);
        }
        hasher.update(&sampling.time_per_cycle.to_le_bytes());
        hasher.update(&(sampling.stored_times.len() as u32).to_le_bytes());
        sampling.stored_times.iter().for_each(|t| hasher.update(&t.to_le_bytes()));
        if let Some(chain) = node.chain {
            hasher.update(&hash_bytes(chain));
        }
        Ok((group, hasher.finish()))
    }

    fn compound_header(&mut self, id: CompoundId, out: &mut Vec<u8>) {
        let (name, metadata) = (self.compounds[id.0].name.clone(), self.compounds[id.0].metadata.serialize());
        let index = self.metadata_index(&metadata);
        let inline_len = if index == info::INLINE_METADATA { metadata.len() } else { 0 };
        let hint = size_hint(name.len().max(inline_len) as u64);
        let word = (hint << info::HINT_SHIFT) | ((index as u32) << info::METADATA_SHIFT);
        out.extend_from_slice(&word.to_le_bytes());
        push_name_and_metadata(out, hint, &name, index, &metadata);
    }

    fn property_header(&mut self, id: PropertyId, out: &mut Vec<u8>) {
        let metadata = self.properties[id.0].metadata.serialize();
        let index = self.metadata_index(&metadata);
        let p = &self.properties[id.0];
        let constant = p.first_changed == 0 && p.last_changed == 0;
        let common_animated = p.first_changed == 1 && p.last_changed + 1 == p.num_samples;
        let explicit = !(constant || common_animated);
        let inline_len = if index == info::INLINE_METADATA { metadata.len() } else { 0 };
        let hint = size_hint(
            (p.name.len().max(inline_len) as u64).max(p.num_samples as u64).max(p.time_sampling as u64),
        );
        let kind = match (p.is_array, p.every_sample_single && p.num_samples > 0) {
            (false, _) => 1,
            (true, false) => 2,
            (true, true) => 3,
        };
        // The reference writer keeps "homogeneous" only for scalars and extent-1 arrays.
        let homogeneous = !p.is_array || p.extent == 1;
        let mut word = kind
            | (hint << info::HINT_SHIFT)
            | ((p.pod.code() as u32) << info::POD_SHIFT)
            | ((p.extent as u32) << info::EXTENT_SHIFT)
            | ((index as u32) << info::METADATA_SHIFT);
        if p.time_sampling != 0 {
            word |= info::HAS_TIME_SAMPLING;
        }
        if explicit {
            word |= info::EXPLICIT_CHANGES;
        }
        if homogeneous {
            word |= info::HOMOGENEOUS;
        }
        if constant {
            word |= info::CONSTANT;
        }
        out.extend_from_slice(&word.to_le_bytes());
        push_sized(out, hint, p.num_samples);
        if explicit {
            push_sized(out, hint, p.first_changed);
            push_sized(out, hint, p.last_changed);
        }
        if p.time_sampling != 0 {
            push_sized(out, hint, p.time_sampling);
        }
        push_name_and_metadata(out, hint, &p.name.clone(), index, &metadata);
    }

    /// Index of a metadata string in the indexed table (added on first use while it has room),
    /// 0 for empty metadata, or 255 when it must be written inline.
    fn metadata_index(&mut self, metadata: &str) -> u8 {
        if metadata.is_empty() {
            return 0;
        }
        if let Some(i) = self.indexed_metadata.iter().position(|m| m == metadata) {
            return i as u8 + 1;
        }
        if metadata.len() < 256 && self.indexed_metadata.len() < 254 {
            self.indexed_metadata.push(metadata.to_string());
            return self.indexed_metadata.len() as u8;
        }
        info::INLINE_METADATA
    }
}

fn push_slot(node: &mut PropertyNode, data: ChildRef) {
    node.slots.push(data);
    if node.is_array {
        // Rank-1 numeric arrays store no dimensions: readers derive the count from the size.
        node.slots.push(ChildRef::EMPTY_DATA);
    }
}

fn push_name_and_metadata(out: &mut Vec<u8>, hint: u32, name: &str, index: u8, metadata: &str) {
    push_sized(out, hint, name.len() as u32);
    out.extend_from_slice(name.as_bytes());
    if index == info::INLINE_METADATA {
        push_sized(out, hint, metadata.len() as u32);
        out.extend_from_slice(metadata.as_bytes());
    }
}
