//! Composition arcs as a layer authors them, the same for `.usda` and `.usdc`: what the parsers
//! record instead of refusing, and what the composer resolves.
use crate::io::usda::Prim;

/// Maps a layer's time codes onto its parent's: `parent = offset + scale * layer`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LayerOffset {
    pub offset: f64,
    pub scale: f64,
}

impl Default for LayerOffset {
    fn default() -> Self {
        LayerOffset { offset: 0.0, scale: 1.0 }
    }
}

impl LayerOffset {
    pub fn apply(self, time: f64) -> f64 {
        self.offset + self.scale * time
    }

    /// The time in the layer that maps onto `time` (the scale is checked positive).
    pub fn invert(self, time: f64) -> f64 {
        (time - self.offset) / self.scale
    }

    /// `self` after `inner`: a time of `inner`'s layer mapped through both.
    pub fn then(self, inner: LayerOffset) -> LayerOffset {
        LayerOffset { offset: self.offset + self.scale * inner.offset, scale: self.scale * inner.scale }
    }

    pub fn is_identity(self) -> bool {
        self == LayerOffset::default()
    }
}

/// A sublayer: its asset path and offset.
#[derive(Clone, Debug, PartialEq)]
pub struct SubLayer {
    pub asset: String,
    pub offset: LayerOffset,
}

/// A reference or payload: `@asset@</Prim>`; an empty asset is internal (this layer stack), no
/// prim path means the target layer's `defaultPrim`.
#[derive(Clone, Debug, PartialEq)]
pub struct AssetArc {
    pub asset: String,
    pub prim_path: Option<String>,
    pub offset: LayerOffset,
}

/// A list edit as USD composes them across layers (`add` counts as `append`; `reorder` only
/// orders and is ignored).
#[derive(Clone, Debug, PartialEq)]
pub struct ListOp<T> {
    /// Set by a plain `key = [...]` (or `None`): replaces every weaker opinion.
    pub explicit: Option<Vec<T>>,
    pub prepended: Vec<T>,
    pub appended: Vec<T>,
    pub deleted: Vec<T>,
}

impl<T> Default for ListOp<T> {
    fn default() -> Self {
        ListOp { explicit: None, prepended: Vec::new(), appended: Vec::new(), deleted: Vec::new() }
    }
}

/// How a list op is spelled before its key.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ListEdit {
    Explicit,
    Prepend,
    Append,
    Delete,
    Reorder,
}

impl ListEdit {
    pub fn from_word(word: &str) -> Option<ListEdit> {
        Some(match word {
            "prepend" => ListEdit::Prepend,
            "append" | "add" => ListEdit::Append,
            "delete" => ListEdit::Delete,
            "reorder" => ListEdit::Reorder,
            _ => return None,
        })
    }
}

impl<T: Clone + PartialEq> ListOp<T> {
    pub fn is_empty(&self) -> bool {
        self.explicit.is_none()
            && self.prepended.is_empty()
            && self.appended.is_empty()
            && self.deleted.is_empty()
    }

    pub fn set(&mut self, edit: ListEdit, items: Vec<T>) {
        match edit {
            ListEdit::Explicit => self.explicit = Some(items),
            ListEdit::Prepend => self.prepended = items,
            ListEdit::Append => self.appended = items,
            ListEdit::Delete => self.deleted = items,
            ListEdit::Reorder => {}
        }
    }

    /// Applies this (stronger) edit over `weaker`, the result of the weaker layers.
    pub fn apply(&self, weaker: Vec<T>) -> Vec<T> {
        if let Some(explicit) = &self.explicit {
            return explicit.clone();
        }
        let mut out: Vec<T> = self.prepended.clone();
        out.extend(weaker.into_iter().filter(|x| {
            !self.deleted.contains(x) && !self.prepended.contains(x) && !self.appended.contains(x)
        }));
        out.extend(self.appended.iter().cloned());
        out
    }
}

/// A variant set as a prim authors it: each variant's body (a prim spec named after the variant).
#[derive(Clone, Debug, Default)]
pub struct VariantSet {
    pub name: String,
    pub variants: Vec<Prim>,
}

/// The composition a prim spec authors. Boxed in [`Prim`]: most prims author none.
#[derive(Clone, Debug, Default)]
pub struct Arcs {
    pub references: ListOp<AssetArc>,
    pub payloads: ListOp<AssetArc>,
    pub inherits: ListOp<String>,
    pub variant_set_names: ListOp<String>,
    /// `variants = { string set = "name" }`.
    pub selections: Vec<(String, String)>,
    pub variant_sets: Vec<VariantSet>,
    /// An arc coif does not compose (`specializes`, `relocates`, value clips): refused when
    /// the prim is composed.
    pub refused: Option<String>,
}

impl Arcs {
    pub fn is_empty(&self) -> bool {
        self.references.is_empty()
            && self.payloads.is_empty()
            && self.inherits.is_empty()
            && self.variant_set_names.is_empty()
            && self.selections.is_empty()
            && self.variant_sets.is_empty()
            && self.refused.is_none()
    }

    pub fn variant_set(&mut self, name: &str) -> &mut VariantSet {
        match self.variant_sets.iter().position(|s| s.name == name) {
            Some(i) => &mut self.variant_sets[i],
            None => {
                self.variant_sets.push(VariantSet { name: name.to_string(), variants: Vec::new() });
                self.variant_sets.last_mut().unwrap()
            }
        }
    }
}

/// The prim metadata of value clips: a dictionary of clip sets (files, prim path, active clips,
/// time mapping, or a template). Clips are not composed: a prim with a clip set is refused, not
/// read as its rest pose (the time samples the clips hold were dropped without a word). The
/// legacy `clipAssetPaths`… keys are not refused: pxr no longer reads them either.
pub const VALUE_CLIPS: &str = "clips";

/// Why the refused arc or metadata `what` stops composition.
pub fn refusal(what: &str) -> String {
    if what == VALUE_CLIPS {
        "value clips are not supported (flatten the stage with usd-core first)".to_string()
    } else {
        format!("'{what}' is not composed by coif (flatten the stage with usd-core first)")
    }
}
