//! Native USD composition, one composer for `.usda` and `.usdc` layers: no Python on the path
//! of a user. Both readers record the arcs a layer authors ([`arcs`]); this module resolves
//! them into one flattened [`Layer`] that the `.usda` reader turns into a groom.
//!
//! What is composed, as Pixar's Pcp does for these arcs:
//! - **subLayers** (with their layer offsets), making a layer stack: the root layer, then each
//!   sublayer's own stack, strongest first;
//! - **references** and **payloads** to other files (`.usda` or `.usdc`, paths relative to the
//!   layer that authors them, or absolute) or internal ones (`</Prim>`), to a prim path or the
//!   target layer's `defaultPrim`, with layer offsets; payloads are all loaded (as
//!   `Usd.Stage.Open` does by default);
//! - **inherits** within the layer stack that authors them;
//! - **variant sets**, with the selection from `--variant` first, else the strongest selection
//!   authored anywhere in the prim's index;
//! - **time code rates**: a sublayer or referenced layer of another `timeCodesPerSecond` (else
//!   `framesPerSecond`, else 24) than the layer naming it has its times scaled by the ratio.
//!
//! Each prim's index is a tree of nodes (sites: a layer stack and a path in it). Its children
//! are ordered by arc (inherits, variants, references, payloads) and then by the namespace depth
//! that introduced them (deeper: stronger), which gives USD's LIVRPS strength order: opinions
//! are read in pre-order, each node's layers strongest first. Values resolve as USD does: the
//! strongest opinion with a value; at a time code, time samples or a default, whichever is
//! stronger. Stage metadata (units, up axis) is the root layer's.
//!
//! Refused with exit 2 naming the file, prim and arc: `specializes`, `relocates` and value
//! `clips` (the animation they hold would be lost under the rest pose), `.usdz`
//! targets, missing files or prims, a missing `defaultPrim`, cycles, and sizes past the limits
//! below (each bounding work a hostile file could otherwise multiply).
pub mod arcs;

use std::cell::RefCell;
use std::collections::{HashMap, HashSet};
use std::path::{Path, PathBuf};
use std::rc::Rc;

use arcs::{Arcs, AssetArc, LayerOffset, ListOp};

use crate::error::{Error, Result};
use crate::groom::Groom;
use crate::io::usda::{self, Attribute, Layer, Prim, Selection, Site, Specifier};
use crate::io::{usdc, ImportOptions};

/// Layers loaded for one stage (a layer read at two different times counts twice).
pub const MAX_LAYERS: usize = 256;
const _: () = assert!(MAX_LAYERS <= u16::MAX as usize, "a Site names its layer in a u16");
/// Arcs nested one inside another (a reference in a referenced layer…).
pub const MAX_ARC_DEPTH: usize = 64;
/// Nodes in one prim's index.
pub const MAX_NODES: usize = 10_000;
/// Prims on the composed stage.
pub const MAX_PRIMS: usize = 1_000_000;
/// Nodes visited over the whole stage: bounds diamonds of references multiplying the work.
pub const MAX_WORK: usize = 5_000_000;
/// Namespace depth of the composed stage.
pub const MAX_NAMESPACE_DEPTH: usize = 512;

/// Reads the groom of a layer that needs composition (already parsed at `selection.time`).
pub fn groom_from_composed(
    root: Layer,
    path: &Path,
    options: &ImportOptions,
    selection: &Selection,
) -> Result<Groom> {
    groom_and_layers(compose(root, path, selection)?, path, options, selection).map(|read| read.groom)
}

/// A composed stage's groom, the layer files it was composed from ([`layers_of`]) and warnings
/// about what reading it left out.
pub struct ComposedGroom {
    pub groom: Groom,
    pub layers: Vec<PathBuf>,
    pub warnings: Vec<String>,
}

/// Reads a `.usda` or `.usdc` stage, composed, into a groom.
pub fn read_groom(path: &Path, options: &ImportOptions, selection: &Selection) -> Result<ComposedGroom> {
    groom_and_layers(read_stage(path, selection)?, path, options, selection)
}

/// [`groom_from_composed`], with the layer files and warnings.
pub fn groom_and_layers_from_composed(
    root: Layer,
    path: &Path,
    options: &ImportOptions,
    selection: &Selection,
) -> Result<ComposedGroom> {
    groom_and_layers(compose(root, path, selection)?, path, options, selection)
}

/// [`groom_and_layers_from_composed`] at the selection's time, reading the `.usda` layers the
/// stage composes from `sampled` (each parsed once for every time it is read at).
pub fn groom_and_layers_from_sampled(
    root: Layer,
    path: &Path,
    options: &ImportOptions,
    selection: &Selection,
    sampled: &SampledLayers,
) -> Result<ComposedGroom> {
    let composed = compose_with(root, path, selection, Some(sampled))?;
    groom_and_layers(composed, path, options, selection)
}

/// `.usda` layers parsed once with all their time samples, each read at any time from memory:
/// the frames of an animated stage that composes a `.usda` cache (a shot layer referencing it)
/// are composed from one parse of each layer, not one a frame. A layer that does not fit in what
/// is left of the budget (its samples take about twice its text) is read from its file each time,
/// as are `.usdc` layers (those read only one time's samples from the mapped file).
pub struct SampledLayers {
    /// By canonical path: the layer with all its samples, or `None` when it is read each time.
    layers: RefCell<HashMap<PathBuf, Option<Rc<Layer>>>>,
    budget: std::cell::Cell<u64>,
}

impl SampledLayers {
    /// Layers whose samples together take at most `budget` bytes.
    pub fn new(budget: u64) -> Self {
        SampledLayers { layers: RefCell::new(HashMap::new()), budget: std::cell::Cell::new(budget) }
    }

    /// The layer at `path` as read at `time`, or `None` when it is to be read from its file.
    fn at(&self, path: &Path, canonical: &Path, time: f64) -> Result<Option<Layer>> {
        if let Some(kept) = self.layers.borrow().get(canonical) {
            return Ok(kept.as_ref().map(|layer| layer.at_time(time)));
        }
        let size = crate::io::kept_samples_size(path);
        let kept = if is_usda(path)? && size <= self.budget.get() {
            self.budget.set(self.budget.get() - size);
            Some(Rc::new(usda::read_layer_between(path, f64::NEG_INFINITY, f64::INFINITY)?))
        } else {
            None
        };
        let layer = kept.as_ref().map(|layer| layer.at_time(time));
        self.layers.borrow_mut().insert(canonical.to_path_buf(), kept);
        Ok(layer)
    }
}

fn groom_and_layers(
    composed: Layer,
    path: &Path,
    options: &ImportOptions,
    selection: &Selection,
) -> Result<ComposedGroom> {
    let layers = layers_of(&composed, path);
    let (groom, warnings) =
        usda::groom_from_layer(composed, path, options, selection.time).map_err(usdc::unline)?;
    Ok(ComposedGroom { groom, layers, warnings })
}

/// The files a stage was read from: the root layer's, then those of the layers it composes.
fn layers_of(stage: &Layer, path: &Path) -> Vec<PathBuf> {
    if stage.sources.is_empty() {
        vec![path.to_path_buf()]
    } else {
        stage.sources.clone()
    }
}

/// Reads a `.usda` or `.usdc` stage and composes it (for the cameras and lights of a render).
pub fn read_stage(path: &Path, selection: &Selection) -> Result<Layer> {
    let layer = load(path, selection.time)?;
    if layer.composes() || !selection.variants.is_empty() {
        compose(layer, path, selection)
    } else {
        Ok(layer)
    }
}

/// Composes the stage whose root layer (at `path`) is `root`.
pub fn compose(root: Layer, path: &Path, selection: &Selection) -> Result<Layer> {
    compose_with(root, path, selection, None)
}

/// [`compose`], reading `.usda` layers from `sampled` when given (and composing at a time).
fn compose_with(
    root: Layer,
    path: &Path,
    selection: &Selection,
    sampled: Option<&SampledLayers>,
) -> Result<Layer> {
    let overrides =
        selection.variants.iter().map(|spec| VariantOverride::parse(spec)).collect::<Result<Vec<_>>>()?;
    let mut composer = Composer {
        sampled,
        time: selection.time,
        layers: Vec::new(),
        layer_ids: HashMap::new(),
        stacks: Vec::new(),
        stack_ids: HashMap::new(),
        overrides,
        prims: 0,
        work: 0,
        next_node: 0,
        index_nodes: 0,
        siblings: RefCell::new(HashMap::new()),
    };
    // The root layer is parsed already: its identity only has to be stable (a layer read from
    // memory has no file to canonicalize).
    let canonical = std::fs::canonicalize(path).unwrap_or_else(|_| path.to_path_buf());
    let meta = (root.meters_per_unit, root.up_axis.clone(), root.default_prim.clone(), root.lines);
    let timeline = root.timeline;
    let root_id = composer.add_layer(canonical.clone(), path.to_path_buf(), selection.time, root)?;
    // Sites index the loaded layers, so the root must be the first: the file being read.
    debug_assert_eq!(root_id, 0);
    let stack = composer.stack_with_root(root_id, &canonical, selection.time, &mut Vec::new())?;
    let mut out = Layer {
        lines: meta.3,
        meters_per_unit: meta.0,
        up_axis: meta.1,
        default_prim: meta.2,
        timeline,
        ..Default::default()
    };
    let mut names: Vec<String> = Vec::new();
    let mut seen = HashSet::new();
    for &(layer, _) in composer.stacks[stack].layers.iter().rev() {
        for prim in &composer.layers[layer].layer.prims {
            if seen.insert(prim.name.as_str()) {
                names.push(prim.name.clone());
            }
        }
    }
    drop(seen);
    for name in names {
        let node = composer.node(
            stack,
            vec![Elem::Child(name.as_str().into())],
            LayerOffset::default(),
            Arc::Root,
            0,
            0,
        );
        if let Some(prim) = composer.prim(&name, "", node, 1)? {
            out.prims.push(prim);
        }
    }
    for o in &composer.overrides {
        if !o.used {
            let problem = match &o.prim {
                Some(prim) => format!("no prim <{prim}> with a variant set '{}'", o.set),
                None => format!("no prim has a variant set '{}'", o.set),
            };
            return Err(Error::format(path, format!("--variant {}: {problem}", o.spec)));
        }
    }
    out.sources = composer.layers.iter().map(|l| l.display.clone()).collect();
    Ok(out)
}

/// Reads one layer file (`.usda` or `.usdc`, told by its first bytes), arcs unresolved.
fn load(path: &Path, time: Option<f64>) -> Result<Layer> {
    if is_usda(path)? {
        usda::read_layer_file(path, time)
    } else {
        usdc::read_layer_file(path, time)
    }
}

/// Whether a layer file is `.usda` (else `.usdc`), told by its first bytes; neither is an error.
fn is_usda(path: &Path) -> Result<bool> {
    // A device or a pipe named by an arc could block or never end.
    crate::io::input::check_regular(path)?;
    let mut head = [0u8; 8];
    let read = std::fs::File::open(path)
        .and_then(|mut f| std::io::Read::read(&mut f, &mut head))
        .map_err(|e| Error::io(path, e))?;
    let head = &head[..read];
    if head.starts_with(usda::MAGIC) {
        Ok(true)
    } else if head.starts_with(usdc::MAGIC) {
        Ok(false)
    } else {
        Err(Error::format(path, "not a .usda or .usdc layer (coif composes those two formats, not .usdz)"))
    }
}

/// `--variant [/Prim/Path:]SET=NAME`.
struct VariantOverride {
    spec: String,
    prim: Option<String>,
    set: String,
    variant: String,
    used: bool,
}

impl VariantOverride {
    fn parse(spec: &str) -> Result<VariantOverride> {
        let (prim, assignment) = match spec.strip_prefix('/') {
            Some(_) => match spec.rsplit_once(':') {
                Some((prim, assignment)) => (Some(prim.to_string()), assignment),
                None => (None, ""),
            },
            None => (None, spec),
        };
        match assignment.split_once('=') {
            Some((set, variant)) if !set.is_empty() && !variant.is_empty() => Ok(VariantOverride {
                spec: spec.to_string(),
                prim,
                set: set.to_string(),
                variant: variant.to_string(),
                used: false,
            }),
            _ => Err(Error::Usage(format!("--variant {spec:?}: expected [PRIM_PATH:]SET=NAME"))),
        }
    }
}

struct LoadedLayer {
    /// The path as the arc named it resolved (for messages), and canonical (for identity).
    display: PathBuf,
    canonical: PathBuf,
    layer: Layer,
}

/// A layer stack: layers strongest first, each with its offset to the stack root's time.
struct Stack {
    root: usize,
    layers: Vec<(usize, LayerOffset)>,
}

/// One element of a site's path. Names are shared: every node of a prim's index, and every
/// child's, copies its parent's path, so a deep index copies names a great many times.
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
enum Elem {
    Child(Rc<str>),
    Variant(Rc<str>, Rc<str>),
}

/// How a node joined the index, in strength order.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
enum Arc {
    Root,
    Inherit,
    Variant,
    Reference,
    Payload,
}

#[derive(Clone)]
struct Node {
    id: usize,
    stack: usize,
    path: Vec<Elem>,
    /// This node's stack-root time → stage time.
    offset: LayerOffset,
    arc: Arc,
    /// Namespace depth of the prim whose spec authored the arc (deeper is stronger).
    depth: usize,
    /// Authored order among arcs of the same kind.
    order: usize,
    children: Vec<Node>,
}

/// One spec's opinions: the spec, its layer and its time mapping to the stage.
struct Opinion<'l> {
    prim: &'l Prim,
    layer: usize,
    offset: LayerOffset,
    arc: Arc,
}

impl Opinion<'_> {
    /// Where a spec of this opinion's layer was authored, on the composed stage.
    fn site(&self, in_layer: Site) -> Site {
        // MAX_LAYERS bounds the index.
        Site { layer: self.layer as u16, line: in_layer.line }
    }
}

struct Composer<'s> {
    sampled: Option<&'s SampledLayers>,
    time: Option<f64>,
    layers: Vec<LoadedLayer>,
    layer_ids: HashMap<(PathBuf, Option<u64>), usize>,
    stacks: Vec<Stack>,
    stack_ids: HashMap<(PathBuf, Option<u64>), usize>,
    overrides: Vec<VariantOverride>,
    prims: usize,
    work: usize,
    next_node: usize,
    /// Nodes in the prim index being built.
    index_nodes: usize,
    siblings: SiblingIndex,
}

/// Sibling lists longer than this are searched through a name index, not one by one (a stage
/// with a prim per strand has 100,000 siblings).
const INDEXED_SIBLINGS: usize = 16;

/// Name → position of the prims in long sibling lists, keyed by the list's address (layers are
/// never changed once loaded, so the address is stable).
type SiblingIndex = RefCell<HashMap<usize, HashMap<String, usize>>>;

fn child<'l>(siblings: &'l [Prim], name: &str, index: &SiblingIndex) -> Option<&'l Prim> {
    if siblings.len() <= INDEXED_SIBLINGS {
        return siblings.iter().find(|p| p.name == name);
    }
    let mut index = index.borrow_mut();
    let names = index
        .entry(siblings.as_ptr() as usize)
        .or_insert_with(|| siblings.iter().enumerate().rev().map(|(i, p)| (p.name.clone(), i)).collect());
    names.get(name).map(|&i| &siblings[i])
}

/// The spec at `path` in `layer`, through children and variant bodies.
fn spec_at<'l>(layer: &'l Layer, path: &[Elem], index: &SiblingIndex) -> Option<&'l Prim> {
    let (Elem::Child(first), rest) = path.split_first()? else { return None };
    let mut prim = child(&layer.prims, first, index)?;
    for elem in rest {
        prim = match elem {
            Elem::Child(name) => child(&prim.children, name, index)?,
            Elem::Variant(set, variant) => {
                let arcs = prim.arcs.as_deref()?;
                let set = arcs.variant_sets.iter().find(|s| *s.name == **set)?;
                set.variants.iter().find(|v| *v.name == **variant)?
            }
        };
    }
    Some(prim)
}

fn path_text(path: &[Elem]) -> String {
    let mut text = String::new();
    for elem in path {
        match elem {
            Elem::Child(name) => {
                text.push('/');
                text.push_str(name);
            }
            Elem::Variant(set, variant) => text.push_str(&format!("{{{set}={variant}}}")),
        }
    }
    text
}

/// `/A/B` as path elements; `None` for anything but an absolute prim path.
fn parse_prim_path(text: &str) -> Option<Vec<Elem>> {
    let rest = text.strip_prefix('/')?;
    let elems: Vec<Elem> = rest.split('/').map(|name| Elem::Child(name.into())).collect();
    let valid = |e: &Elem| matches!(e, Elem::Child(n) if !n.is_empty() && n.chars().all(|c| c.is_alphanumeric() || c == '_'));
    elems.iter().all(valid).then_some(elems)
}

fn time_key(time: Option<f64>) -> Option<u64> {
    time.map(f64::to_bits)
}

impl Composer<'_> {
    fn add_layer(
        &mut self,
        canonical: PathBuf,
        display: PathBuf,
        time: Option<f64>,
        layer: Layer,
    ) -> Result<usize> {
        if self.layers.len() >= MAX_LAYERS {
            return Err(Error::format(&display, format!("the stage loads more than {MAX_LAYERS} layers")));
        }
        if let Some((line, what)) = &layer.refused {
            let at = if *line > 0 { format!("line {line}: ") } else { String::new() };
            return Err(Error::format(&display, format!("{at}'{what}' is not composed by coif")));
        }
        let id = self.layers.len();
        self.layer_ids.insert((canonical.clone(), time_key(time)), id);
        self.layers.push(LoadedLayer { display, canonical, layer });
        Ok(id)
    }

    /// The layer at `path` read at `time` (its own time codes), loaded once.
    fn layer(&mut self, path: &Path, time: Option<f64>) -> Result<usize> {
        let canonical = std::fs::canonicalize(path).map_err(|e| Error::io(path, e))?;
        if let Some(&id) = self.layer_ids.get(&(canonical.clone(), time_key(time))) {
            return Ok(id);
        }
        let sampled = match (self.sampled, time) {
            (Some(sampled), Some(time)) => sampled.at(path, &canonical, time)?,
            _ => None,
        };
        let layer = match sampled {
            Some(layer) => layer,
            None => load(path, time)?,
        };
        self.add_layer(canonical, path.to_path_buf(), time, layer)
    }

    /// The layer stack rooted at the layer file `path`, read at its own `time`.
    fn stack(&mut self, path: &Path, time: Option<f64>, chain: &mut Vec<PathBuf>) -> Result<usize> {
        let root = self.layer(path, time)?;
        let canonical = self.layers[root].canonical.clone();
        self.stack_with_root(root, &canonical, time, chain)
    }

    /// The layer stack of `path` reached through `offset` from a layer of `rate` time codes per
    /// second, read at the time `time` of that layer maps to, and the offset from its time: when
    /// its own rate differs, its times are scaled by the ratio, as USD does (a 24-per-second
    /// layer's time 24 is time 48 of a 48-per-second stage). The rate is known once the layer is
    /// read, so a layer of another rate is read again at the time it then maps to.
    fn stack_in_time(
        &mut self,
        path: &Path,
        offset: LayerOffset,
        rate: f64,
        time: Option<f64>,
        chain: &mut Vec<PathBuf>,
    ) -> Result<(usize, LayerOffset)> {
        let stack = self.stack(path, time.map(|t| offset.invert(t)), chain)?;
        let own_rate = self.layers[self.stacks[stack].root].layer.timeline.codes_per_second();
        if own_rate == rate {
            return Ok((stack, offset));
        }
        let offset = offset.then(LayerOffset { offset: 0.0, scale: rate / own_rate });
        Ok((self.stack(path, time.map(|t| offset.invert(t)), chain)?, offset))
    }

    fn stack_with_root(
        &mut self,
        root: usize,
        canonical: &Path,
        time: Option<f64>,
        chain: &mut Vec<PathBuf>,
    ) -> Result<usize> {
        let key = (canonical.to_path_buf(), time_key(time));
        if let Some(&id) = self.stack_ids.get(&key) {
            return Ok(id);
        }
        if chain.iter().any(|p| p == canonical) {
            let display = &self.layers[root].display;
            return Err(Error::format(display, "subLayers form a cycle (the layer is its own sublayer)"));
        }
        if chain.len() >= MAX_ARC_DEPTH {
            let display = &self.layers[root].display;
            return Err(Error::format(display, format!("subLayers nest deeper than {MAX_ARC_DEPTH}")));
        }
        chain.push(canonical.to_path_buf());
        let mut layers = vec![(root, LayerOffset::default())];
        let sub_layers = self.layers[root].layer.sub_layers.clone();
        let display = self.layers[root].display.clone();
        let rate = self.layers[root].layer.timeline.codes_per_second();
        for sub in sub_layers {
            let target = resolve(&display, &sub.asset);
            let arc = || format!("subLayer @{}@", sub.asset);
            check_offset(sub.offset, &display, &arc)?;
            let (stack, offset) = self
                .stack_in_time(&target, sub.offset, rate, time, chain)
                .map_err(|e| in_arc(e, &display, &arc()))?;
            // A layer already in the stack is stronger there and shadows every opinion of its
            // weaker repeat (the same specs; list ops compose to the same list): it is taken
            // once, so layers listing their sublayers twice do not double the stack per level.
            for &(layer, inner) in &self.stacks[stack].layers {
                if !layers.iter().any(|&(seen, _)| seen == layer) {
                    layers.push((layer, offset.then(inner)));
                }
            }
        }
        chain.pop();
        let id = self.stacks.len();
        self.stacks.push(Stack { root, layers });
        self.stack_ids.insert(key, id);
        Ok(id)
    }

    fn node(
        &mut self,
        stack: usize,
        path: Vec<Elem>,
        offset: LayerOffset,
        arc: Arc,
        depth: usize,
        order: usize,
    ) -> Node {
        self.next_node += 1;
        self.index_nodes += 1;
        Node { id: self.next_node, stack, path, offset, arc, depth, order, children: Vec::new() }
    }

    /// The specs of a node's site, strongest first, with their layers' time offsets.
    fn specs(&self, node: &Node) -> Vec<(&Prim, usize, LayerOffset)> {
        self.stacks[node.stack]
            .layers
            .iter()
            .filter_map(|&(layer, offset)| {
                spec_at(&self.layers[layer].layer, &node.path, &self.siblings)
                    .map(|p| (p, layer, node.offset.then(offset)))
            })
            .collect()
    }

    /// A list op composed over a node's specs (weakest first), each item with the layer that
    /// authored it and that layer's offset.
    fn composed<T: Clone + PartialEq>(
        &self,
        node: &Node,
        field: impl Fn(&Arcs) -> &ListOp<T>,
    ) -> Vec<(T, usize, LayerOffset)> {
        let mut items: Vec<T> = Vec::new();
        let mut owner: Vec<(T, usize, LayerOffset)> = Vec::new();
        for (spec, layer, offset) in self.specs(node).into_iter().rev() {
            if let Some(arcs) = spec.arcs.as_deref() {
                let op = field(arcs);
                items = op.apply(items);
                for item in op.explicit.iter().flatten().chain(&op.prepended).chain(&op.appended) {
                    owner.retain(|(x, _, _)| x != item);
                    owner.push((item.clone(), layer, offset));
                }
            }
        }
        items
            .into_iter()
            .map(|item| {
                let (_, layer, offset) =
                    owner.iter().find(|(x, _, _)| *x == item).cloned().expect("recorded above");
                (item, layer, offset)
            })
            .collect()
    }

    /// Adds the inherits, references and payloads a node's specs author (and theirs, nested).
    fn expand(
        &mut self,
        node: &mut Node,
        depth: usize,
        chain: &mut Vec<(usize, Vec<Elem>)>,
        stage_path: &str,
    ) -> Result<()> {
        self.work += 1;
        if self.index_nodes > MAX_NODES {
            return Err(self.error(
                node,
                stage_path,
                format!("the prim's index has more than {MAX_NODES} nodes"),
            ));
        }
        if self.work > MAX_WORK {
            return Err(self.error(
                node,
                stage_path,
                format!("composition visits more than {MAX_WORK} nodes"),
            ));
        }
        if let Some((spec, layer, _)) = self
            .specs(node)
            .into_iter()
            .find(|(s, _, _)| s.arcs.as_ref().is_some_and(|a| a.refused.is_some()))
        {
            let what = spec.arcs.as_ref().and_then(|a| a.refused.clone()).unwrap_or_default();
            let display = self.layers[layer].display.clone();
            return Err(Error::format(&display, format!("prim <{stage_path}>: {}", arcs::refusal(&what))));
        }
        let inherits = self.composed(node, |a| &a.inherits);
        let references = self.composed(node, |a| &a.references);
        let payloads = self.composed(node, |a| &a.payloads);
        let mut added = Vec::new();
        for (order, (target, layer, _)) in inherits.into_iter().enumerate() {
            let arc = format!("inherits <{target}>");
            let path = parse_prim_path(&target)
                .ok_or_else(|| self.arc_error(layer, stage_path, &arc, "the target is not a prim path"))?;
            added.push(self.node(node.stack, path, node.offset, Arc::Inherit, depth, order));
        }
        for (kind, list) in [(Arc::Reference, references), (Arc::Payload, payloads)] {
            for (order, (target, layer, layer_offset)) in list.into_iter().enumerate() {
                let added_node =
                    self.asset_node(node, &target, layer, layer_offset, kind, depth, order, stage_path)?;
                added.push(added_node);
            }
        }
        for mut child in added {
            let site = (self.stacks[child.stack].root, child.path.clone());
            if chain.contains(&site) || (self.stacks[node.stack].root, node.path.clone()) == site {
                return Err(self.error(
                    &child,
                    stage_path,
                    format!(
                        "composition cycle: {} reaches <{}> again",
                        arc_name(child.arc),
                        path_text(&child.path)
                    ),
                ));
            }
            if chain.len() >= MAX_ARC_DEPTH {
                return Err(self.error(&child, stage_path, format!("arcs nest deeper than {MAX_ARC_DEPTH}")));
            }
            chain.push((self.stacks[node.stack].root, node.path.clone()));
            let result = self.expand(&mut child, depth, chain, stage_path);
            chain.pop();
            result?;
            node.children.push(child);
        }
        sort_children(node);
        Ok(())
    }

    /// The node a reference or payload adds.
    #[allow(clippy::too_many_arguments)]
    fn asset_node(
        &mut self,
        node: &Node,
        target: &AssetArc,
        layer: usize,
        layer_offset: LayerOffset,
        kind: Arc,
        depth: usize,
        order: usize,
        stage_path: &str,
    ) -> Result<Node> {
        let arc = format!(
            "{} @{}@{}",
            arc_name(kind),
            target.asset,
            target.prim_path.as_deref().map(|p| format!("<{p}>")).unwrap_or_default()
        );
        let authored_in = self.layers[layer].display.clone();
        check_offset(target.offset, &authored_in, &|| format!("prim <{stage_path}>: {arc}"))?;
        let mut offset = layer_offset.then(target.offset);
        let stack = if target.asset.is_empty() {
            node.stack
        } else {
            let file = resolve(&authored_in, &target.asset);
            // The target's times scale by its rate against the layer that authors the arc.
            let rate = self.layers[layer].layer.timeline.codes_per_second();
            let (stack, scaled) = self
                .stack_in_time(&file, offset, rate, self.time, &mut Vec::new())
                .map_err(|e| in_arc(e, &authored_in, &format!("prim <{stage_path}>: {arc}")))?;
            offset = scaled;
            stack
        };
        let root_layer = &self.layers[self.stacks[stack].root];
        let prim_path = match &target.prim_path {
            Some(path) => path.clone(),
            None => match &root_layer.layer.default_prim {
                Some(name) => format!("/{name}"),
                None => {
                    let problem =
                        format!("{} names no prim and has no defaultPrim", root_layer.display.display());
                    return Err(self.arc_error(layer, stage_path, &arc, &problem));
                }
            },
        };
        let path = parse_prim_path(&prim_path).ok_or_else(|| {
            self.arc_error(layer, stage_path, &arc, &format!("<{prim_path}> is not a prim path"))
        })?;
        let new = self.node(stack, path, offset, kind, depth, order);
        if self.specs(&new).is_empty() {
            let problem = format!(
                "{} has no prim <{prim_path}>",
                self.layers[self.stacks[stack].root].display.display()
            );
            return Err(self.arc_error(layer, stage_path, &arc, &problem));
        }
        Ok(new)
    }

    fn arc_error(&self, layer: usize, stage_path: &str, arc: &str, problem: &str) -> Error {
        Error::format(&self.layers[layer].display, format!("prim <{stage_path}>: {arc}: {problem}"))
    }

    fn error(&self, node: &Node, stage_path: &str, problem: String) -> Error {
        let layer = self.stacks[node.stack].root;
        Error::format(&self.layers[layer].display, format!("prim <{stage_path}>: {problem}"))
    }

    /// Selects and adds variants until every variant set in the index has been considered.
    fn select_variants(&mut self, root: &mut Node, depth: usize, stage_path: &str) -> Result<()> {
        let mut done: HashSet<(usize, String)> = HashSet::new();
        loop {
            // The first node (in strength order) with a variant set not yet considered.
            let mut pending = None;
            visit(root, &mut |node| {
                if pending.is_some() {
                    return;
                }
                for (set, _, _) in self.composed(node, |a| &a.variant_set_names) {
                    if !done.contains(&(node.id, set.clone())) {
                        pending = Some((node.id, set));
                        return;
                    }
                }
            });
            let Some((id, set)) = pending else { return Ok(()) };
            done.insert((id, set.clone()));
            let selection = self.selection(root, &set, stage_path)?;
            let Some(variant) = selection else { continue };
            let node = find(root, id).expect("found above");
            let mut path = node.path.clone();
            path.push(Elem::Variant(set.as_str().into(), variant.into()));
            let (stack, offset) = (node.stack, node.offset);
            let mut child = self.node(stack, path, offset, Arc::Variant, depth, 0);
            if self.specs(&child).is_empty() {
                continue;
            }
            self.expand(&mut child, depth, &mut Vec::new(), stage_path)?;
            let node = find(root, id).expect("found above");
            node.children.push(child);
            sort_children(node);
            self.count_nodes(root, stage_path)?;
        }
    }

    /// The variant chosen for `set` on this prim: `--variant`, else the strongest authored.
    fn selection(&mut self, root: &Node, set: &str, stage_path: &str) -> Result<Option<String>> {
        let index = self
            .overrides
            .iter()
            .position(|o| o.set == set && o.prim.as_deref().is_none_or(|p| p == stage_path));
        if let Some(i) = index {
            let mut names = Vec::new();
            visit(root, &mut |node| {
                for (spec, _, _) in self.specs(node) {
                    for s in spec.arcs.iter().flat_map(|a| &a.variant_sets).filter(|s| s.name == set) {
                        for v in &s.variants {
                            if !names.contains(&v.name) {
                                names.push(v.name.clone());
                            }
                        }
                    }
                }
            });
            let o = &mut self.overrides[i];
            if !names.contains(&o.variant) {
                let layer = self.stacks[root.stack].root;
                return Err(Error::format(
                    &self.layers[layer].display,
                    format!(
                        "--variant {}: <{stage_path}> has no variant '{}' in set '{set}' (it has {})",
                        o.spec,
                        o.variant,
                        names.join(", ")
                    ),
                ));
            }
            o.used = true;
            return Ok(Some(o.variant.clone()));
        }
        let mut chosen = None;
        visit(root, &mut |node| {
            if chosen.is_some() {
                return;
            }
            for (spec, _, _) in self.specs(node) {
                if let Some((_, v)) = spec.arcs.iter().flat_map(|a| &a.selections).find(|(s, _)| s == set) {
                    chosen = Some(v.clone());
                    return;
                }
            }
        });
        Ok(chosen.filter(|v| !v.is_empty()))
    }

    fn count_nodes(&self, root: &Node, stage_path: &str) -> Result<()> {
        let mut count = 0;
        visit(root, &mut |_| count += 1);
        if count > MAX_NODES {
            return Err(self.error(
                root,
                stage_path,
                format!("the prim's index has more than {MAX_NODES} nodes"),
            ));
        }
        Ok(())
    }

    /// Composes the prim `name` under `parent_path` from its index's root `node` (the parent's
    /// index carried down, or the root layer stack's site); `None` where no layer has a spec.
    fn prim(&mut self, name: &str, parent_path: &str, mut root: Node, depth: usize) -> Result<Option<Prim>> {
        let stage_path = format!("{parent_path}/{name}");
        if depth > MAX_NAMESPACE_DEPTH {
            return Err(self.error(
                &root,
                &stage_path,
                format!("prims nest deeper than {MAX_NAMESPACE_DEPTH}"),
            ));
        }
        self.prims += 1;
        if self.prims > MAX_PRIMS {
            return Err(self.error(
                &root,
                &stage_path,
                format!("the stage composes more than {MAX_PRIMS} prims"),
            ));
        }
        // Arcs authored at this prim's sites, on every node carried down from the parent.
        self.index_nodes = 0;
        visit(&root, &mut |_| self.index_nodes += 1);
        expand_all(self, &mut root, depth, &stage_path)?;
        self.select_variants(&mut root, depth, &stage_path)?;
        self.count_nodes(&root, &stage_path)?;

        let mut opinions: Vec<Opinion> = Vec::new();
        visit(&root, &mut |node| {
            for (prim, layer, offset) in self.specs(node) {
                opinions.push(Opinion { prim, layer, offset, arc: node.arc });
            }
        });
        if opinions.is_empty() {
            return Ok(None);
        }
        let mut prim = compose_fields(name, &opinions, self.time);
        let mut child_names: Vec<String> = Vec::new();
        let mut seen = HashSet::new();
        for opinion in opinions.iter().rev() {
            for child in &opinion.prim.children {
                if seen.insert(child.name.as_str()) {
                    child_names.push(child.name.clone());
                }
            }
        }
        drop(seen);
        drop(opinions);
        for child in child_names {
            if let Some(node) = derive(self, &root, &child) {
                if let Some(composed) = self.prim(&child, &stage_path, node, depth + 1)? {
                    prim.children.push(composed);
                }
            }
        }
        Ok(Some(prim))
    }
}

/// Expands every node of the index (in pre-order) at its current site; new nodes are expanded
/// as they are added.
fn expand_all(composer: &mut Composer, node: &mut Node, depth: usize, stage_path: &str) -> Result<()> {
    let carried = std::mem::take(&mut node.children);
    composer.expand(node, depth, &mut Vec::new(), stage_path)?;
    for mut child in carried {
        expand_all(composer, &mut child, depth, stage_path)?;
        node.children.push(child);
    }
    sort_children(node);
    Ok(())
}

/// The node `node` becomes for the child prim `name`, dropping sites with no specs below.
fn derive(composer: &Composer, node: &Node, name: &str) -> Option<Node> {
    let mut path = node.path.clone();
    path.push(Elem::Child(name.into()));
    let children: Vec<Node> = node.children.iter().filter_map(|c| derive(composer, c, name)).collect();
    // Field by field: `..node.clone()` would copy the whole subtree only to drop it, making a
    // deep index quadratic (a fan of references took 77 s to reach the work limit).
    let Node { id, stack, offset, arc, depth, order, .. } = *node;
    let derived = Node { id, stack, path, offset, arc, depth, order, children };
    let has_specs = !composer.specs(&derived).is_empty();
    (has_specs || !derived.children.is_empty() || derived.arc == Arc::Root).then_some(derived)
}

fn sort_children(node: &mut Node) {
    node.children.sort_by_key(|c| (c.arc, std::cmp::Reverse(c.depth), c.order));
}

fn visit<'n>(node: &'n Node, f: &mut impl FnMut(&'n Node)) {
    f(node);
    for child in &node.children {
        visit(child, f);
    }
}

fn find(node: &mut Node, id: usize) -> Option<&mut Node> {
    if node.id == id {
        return Some(node);
    }
    node.children.iter_mut().find_map(|c| find(c, id))
}

fn arc_name(arc: Arc) -> &'static str {
    match arc {
        Arc::Root => "root",
        Arc::Inherit => "inherits",
        Arc::Variant => "variant",
        Arc::Reference => "reference",
        Arc::Payload => "payload",
    }
}

/// An asset path relative to the layer that names it (or absolute).
fn resolve(anchor: &Path, asset: &str) -> PathBuf {
    let asset = Path::new(asset);
    if asset.is_absolute() {
        asset.to_path_buf()
    } else {
        anchor.parent().unwrap_or(Path::new(".")).join(asset)
    }
}

fn check_offset(offset: LayerOffset, file: &Path, arc: &dyn Fn() -> String) -> Result<()> {
    if !offset.offset.is_finite() || !offset.scale.is_finite() || offset.scale <= 0.0 {
        return Err(Error::format(
            file,
            format!(
                "{}: layer offset {} scale {} (the scale must be finite and positive)",
                arc(),
                offset.offset,
                offset.scale
            ),
        ));
    }
    Ok(())
}

/// An error met while following an arc, said to come through it.
fn in_arc(error: Error, authored_in: &Path, arc: &str) -> Error {
    match error {
        Error::Format { path, message } if path != authored_in => {
            Error::format(authored_in, format!("{arc}: {}: {message}", path.display()))
        }
        Error::Io { path, source } => {
            Error::format(authored_in, format!("{arc}: cannot read {}: {source}", path.display()))
        }
        other => other,
    }
}

/// The composed prim's own fields: type, specifier, active, attributes (children come later).
fn compose_fields(name: &str, opinions: &[Opinion], time: Option<f64>) -> Prim {
    let strongest = &opinions[0];
    let specifier = opinions
        .iter()
        .map(|o| match (o.arc, o.prim.specifier) {
            // A class one inherits from does not make the inheriting prim abstract.
            (Arc::Inherit, Specifier::Class) => Specifier::Over,
            (_, specifier) => specifier,
        })
        .find(|s| *s != Specifier::Over)
        .unwrap_or(Specifier::Over);
    let mut prim = Prim {
        name: name.to_string(),
        type_name: opinions
            .iter()
            .map(|o| &o.prim.type_name)
            .find(|t| !t.is_empty())
            .cloned()
            .unwrap_or_default(),
        site: strongest.site(strongest.prim.site),
        specifier,
        active: opinions.iter().find_map(|o| o.prim.active),
        ..Default::default()
    };
    let mut names: Vec<&str> = Vec::new();
    for opinion in opinions.iter().rev() {
        for attribute in &opinion.prim.attributes {
            if !names.contains(&attribute.name.as_str()) {
                names.push(&attribute.name);
            }
        }
    }
    for attribute_name in names {
        let specs: Vec<(&Attribute, &Opinion)> = opinions
            .iter()
            .filter_map(|o| o.prim.attributes.iter().find(|a| a.name == attribute_name).map(|a| (a, o)))
            .collect();
        // At a time, the strongest opinion with a value (samples before a default within it); at
        // the default time, the strongest default, else that opinion's earliest sample.
        let timed = specs.iter().find(|(a, _)| a.default.is_some() || !a.samples.is_empty());
        let source = match time {
            None => specs.iter().find(|(a, _)| a.default.is_some()).or(timed),
            Some(_) => timed,
        };
        // The strongest declaration's type.
        let declared = specs.iter().map(|(a, _)| a).find(|a| !a.type_name.is_empty());
        let mut attribute = Attribute {
            name: attribute_name.to_string(),
            type_name: declared.map(|a| a.type_name.clone()).unwrap_or_default(),
            array: declared.is_some_and(|a| a.array),
            interpolation: specs.iter().find_map(|(a, _)| a.interpolation.clone()),
            element_size: specs.iter().find_map(|(a, _)| a.element_size),
            ..Default::default()
        };
        if let Some((spec, opinion)) = source.or(specs.first()) {
            attribute.site = opinion.site(spec.site);
        }
        if let Some((spec, _)) = source {
            attribute.default = spec.default.clone();
        }
        // Kept at the default time too, where the default is read before them: they tell that
        // the attribute is animated (a cache with a rest pose as its default and the motion as
        // samples, reached through a sublayer or reference, read as still when they were dropped).
        if let Some((spec, opinion)) = timed {
            attribute.samples =
                spec.samples.iter().map(|(t, v)| (opinion.offset.apply(*t), v.clone())).collect();
        }
        prim.attributes.push(attribute);
    }
    prim
}
