//! Meshes: the data model shared by every stage, read from Gmsh MSH files ([`msh`]).
//!
//! Conventions (`docs/conventions.md` §1): nodes get a compact 0-based index in ascending Gmsh node-tag
//! order; the tag is kept for output. Elements are stored in blocks of one type that share their
//! elementary entity and physical tags, with connectivity as node *indices* in Gmsh's node ordering
//! (see [`element`]). Physical groups are resolved to element blocks, and from them to node sets,
//! by name.

mod ascii;
pub mod element;
pub mod faces;
pub mod msh;

use std::collections::BTreeMap;
use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};

use rayon::prelude::*;

pub use element::ElementType;

use crate::error::{Error, Result};

/// Which MSH variant a mesh was read from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct MshFormat {
    /// `2.2` or `4.1` (as read from `$MeshFormat`).
    pub version: MshVersion,
    /// Binary (`file-type` 1) or ASCII.
    pub binary: bool,
    /// For binary files: whether the file's byte order differs from little-endian.
    pub big_endian: bool,
}

/// The MSH versions nlrom reads.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MshVersion {
    V22,
    V41,
}

impl MshVersion {
    /// `"2.2"` or `"4.1"`.
    pub fn as_str(self) -> &'static str {
        match self {
            MshVersion::V22 => "2.2",
            MshVersion::V41 => "4.1",
        }
    }
}

/// Elements of one type on one elementary entity, with the same physical tags.
#[derive(Clone, Debug, PartialEq)]
pub struct ElementBlock {
    /// The element type (all elements of the block).
    pub kind: ElementType,
    /// Tag of the elementary entity (dimension = `kind.dim()`); 0 when the file gives none.
    pub entity: i32,
    /// Physical tags (dimension = `kind.dim()`) the elements belong to.
    pub physicals: Vec<i32>,
    /// Gmsh element tags, one per element.
    pub tags: ElementTags,
    /// Node indices, `kind.num_nodes()` per element, in Gmsh order.
    pub connectivity: Vec<u32>,
}

impl ElementBlock {
    /// Number of elements in the block.
    pub fn len(&self) -> usize {
        self.tags.len()
    }

    /// Whether the block has no element.
    pub fn is_empty(&self) -> bool {
        self.tags.is_empty()
    }

    /// Node indices of element `e` of the block.
    pub fn element(&self, e: usize) -> &[u32] {
        let n = self.kind.num_nodes();
        &self.connectivity[e * n..(e + 1) * n]
    }

    /// Iterator over the elements' node-index slices.
    pub fn elements(&self) -> std::slice::ChunksExact<'_, u32> {
        self.connectivity.chunks_exact(self.kind.num_nodes())
    }
}

/// The Gmsh tags of the elements of a block, in element order.
///
/// Gmsh numbers the elements of a block consecutively, so the usual block is a run `first,
/// first + 1, …`, held as its first tag and length without an array; any other sequence is held
/// as the list of its tags. The constructors and [`ElementTags::push`] keep a run as long as the
/// tags run on, so equal sequences have equal representations.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum ElementTags {
    /// `len` tags `first, first + 1, …, first + len − 1`.
    Run { first: u64, len: usize },
    /// Any other sequence.
    List(Vec<u64>),
}

impl Default for ElementTags {
    fn default() -> Self {
        ElementTags::Run { first: 0, len: 0 }
    }
}

impl ElementTags {
    /// The number of tags.
    pub fn len(&self) -> usize {
        match self {
            ElementTags::Run { len, .. } => *len,
            ElementTags::List(v) => v.len(),
        }
    }

    /// Whether there is no tag.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The tag of element `e` (panics if `e` is out of range, as indexing does).
    pub fn at(&self, e: usize) -> u64 {
        match self {
            ElementTags::Run { first, len } => {
                assert!(e < *len, "element {e} of a block of {len}");
                first + e as u64
            }
            ElementTags::List(v) => v[e],
        }
    }

    /// The tags in element order.
    pub fn iter(&self) -> impl Iterator<Item = u64> + '_ {
        let (first, len, list) = match self {
            ElementTags::Run { first, len } => (*first, *len as u64, &[][..]),
            ElementTags::List(v) => (0, 0, &v[..]),
        };
        (0..len).map(move |k| first + k).chain(list.iter().copied())
    }

    /// Appends `tag`: a run grows while the tags run on, else becomes a list.
    pub fn push(&mut self, tag: u64) {
        match self {
            ElementTags::Run { len: 0, .. } => *self = ElementTags::Run { first: tag, len: 1 },
            ElementTags::Run { first, len } if first.checked_add(*len as u64) == Some(tag) => {
                *len += 1
            }
            ElementTags::Run { first, len } => {
                let mut v: Vec<u64> = (0..*len as u64).map(|k| *first + k).collect();
                v.push(tag);
                *self = ElementTags::List(v);
            }
            ElementTags::List(v) => v.push(tag),
        }
    }

    /// Appends the tags of `other`.
    pub fn extend(&mut self, other: &ElementTags) {
        if self.is_empty() {
            *self = other.clone();
            return;
        }
        if let (ElementTags::Run { first, len }, &ElementTags::Run { first: f, len: l }) =
            (&mut *self, other)
        {
            if first.checked_add(*len as u64) == Some(f) {
                *len += l;
                return;
            }
        }
        match self {
            ElementTags::List(v) => v.extend(other.iter()),
            ElementTags::Run { .. } => other.iter().for_each(|t| self.push(t)),
        }
    }
}

impl From<Vec<u64>> for ElementTags {
    /// A run if the tags run on (the vector is dropped), else the list.
    fn from(v: Vec<u64>) -> Self {
        let run = v.windows(2).all(|w| w[0].checked_add(1) == Some(w[1]));
        match v.first() {
            Some(&first) if run => ElementTags::Run {
                first,
                len: v.len(),
            },
            None => ElementTags::default(),
            Some(_) => ElementTags::List(v),
        }
    }
}

impl FromIterator<u64> for ElementTags {
    fn from_iter<I: IntoIterator<Item = u64>>(iter: I) -> Self {
        let mut tags = ElementTags::default();
        iter.into_iter().for_each(|t| tags.push(t));
        tags
    }
}

/// A physical group: a name, a dimension and a tag (`$PhysicalNames`).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct PhysicalGroup {
    /// Name from `$PhysicalNames`; groups without one are named by their tag (`"dim2_tag7"`).
    pub name: String,
    /// Dimension 0..=3.
    pub dim: u8,
    /// Physical tag.
    pub tag: i32,
}

/// A `$Periodic` link between two entities: node pairs (indices) and the affine map, if given.
///
/// Gmsh lists only the corner nodes for second-order meshes; do not rely on this for mid-edge nodes.
#[derive(Clone, Debug, PartialEq)]
pub struct PeriodicLink {
    /// Dimension of the linked entities.
    pub dim: u8,
    /// The slave (image) entity tag.
    pub entity: i32,
    /// The master entity tag.
    pub master: i32,
    /// Row-major 4×4 affine transform that maps master positions to slave positions (empty if
    /// the file gives none).
    pub affine: Vec<f64>,
    /// (slave node index, master node index).
    pub nodes: Vec<(u32, u32)>,
}

/// A mesh as read from a Gmsh file.
#[derive(Clone, Debug, PartialEq)]
pub struct Mesh {
    /// The file it was read from, for messages.
    pub source: Option<PathBuf>,
    /// Version and encoding of the file.
    pub format: MshFormat,
    /// Gmsh node tags, ascending; index = compact node index.
    pub node_tags: Vec<u64>,
    /// Coordinates (m) of each node, by node index.
    pub coords: Vec<[f64; 3]>,
    /// Element blocks in file order.
    pub blocks: Vec<ElementBlock>,
    /// Physical groups, in the order of `$PhysicalNames` and then of first use.
    pub groups: Vec<PhysicalGroup>,
    /// `$Periodic` links.
    pub periodic: Vec<PeriodicLink>,
}

impl Mesh {
    /// Number of nodes.
    pub fn num_nodes(&self) -> usize {
        self.node_tags.len()
    }

    /// Total number of elements over all blocks.
    pub fn num_elements(&self) -> usize {
        self.blocks.iter().map(ElementBlock::len).sum()
    }

    /// Element counts by type, in type order.
    pub fn element_counts(&self) -> BTreeMap<ElementType, usize> {
        let mut counts = BTreeMap::new();
        for b in &self.blocks {
            *counts.entry(b.kind).or_insert(0) += b.len();
        }
        counts
    }

    /// The file name for messages (`<memory>` when parsed from bytes).
    pub fn source_name(&self) -> String {
        self.source
            .as_ref()
            .map(|p| p.display().to_string())
            .unwrap_or_else(|| "<memory>".to_string())
    }

    /// The physical group called `name`, or an error that names the file and lists the groups there are.
    pub fn group(&self, name: &str) -> Result<&PhysicalGroup> {
        self.groups.iter().find(|g| g.name == name).ok_or_else(|| {
            let names: Vec<&str> = self.groups.iter().map(|g| g.name.as_str()).collect();
            Error::input(format!(
                "{}: no physical group named '{}'; the mesh has: {}. Add it in Gmsh (Physical Surface/Volume/Point) or correct the name in the case file",
                self.source_name(),
                name,
                if names.is_empty() { "none".to_string() } else { names.join(", ") }
            ))
        })
    }

    /// The blocks whose elements belong to `group` (same dimension and a matching physical tag).
    pub fn group_blocks<'a>(
        &'a self,
        group: &'a PhysicalGroup,
    ) -> impl Iterator<Item = &'a ElementBlock> + 'a {
        self.blocks
            .iter()
            .filter(move |b| b.kind.dim() == group.dim && b.physicals.contains(&group.tag))
    }

    /// Number of elements in `group`.
    pub fn group_element_count(&self, group: &PhysicalGroup) -> usize {
        self.group_blocks(group).map(ElementBlock::len).sum()
    }

    /// Which nodes the elements of `group` use, one flag per node (marked in parallel).
    fn group_node_marks(&self, group: &PhysicalGroup) -> Vec<AtomicBool> {
        let used: Vec<AtomicBool> = (0..self.num_nodes())
            .map(|_| AtomicBool::new(false))
            .collect();
        let marks = used.as_slice();
        for b in self.group_blocks(group) {
            b.connectivity.par_chunks(1 << 16).for_each(|chunk| {
                for &n in chunk {
                    marks[n as usize].store(true, Ordering::Relaxed);
                }
            });
        }
        used
    }

    /// Sorted, distinct node indices of the elements of `group` (marked in parallel).
    pub fn group_node_indices(&self, group: &PhysicalGroup) -> Vec<u32> {
        self.group_node_marks(group)
            .iter()
            .enumerate()
            .filter_map(|(i, u)| u.load(Ordering::Relaxed).then_some(i as u32))
            .collect()
    }

    /// The number of distinct nodes of the elements of `group`: the length of
    /// [`Mesh::group_node_indices`] without building the list.
    pub fn group_node_count(&self, group: &PhysicalGroup) -> usize {
        self.group_node_marks(group)
            .into_iter()
            .map(|u| usize::from(u.into_inner()))
            .sum()
    }

    /// Sorted node indices of the group called `name` (error if it does not exist or is empty).
    pub fn nodes_of(&self, name: &str) -> Result<Vec<u32>> {
        let g = self.group(name)?;
        let nodes = self.group_node_indices(g);
        if nodes.is_empty() {
            return Err(Error::input(format!(
                "{}: physical group '{}' (dim {}, tag {}) has no elements, so no nodes",
                self.source_name(),
                name,
                g.dim,
                g.tag
            )));
        }
        Ok(nodes)
    }

    /// The compact index of the node with Gmsh tag `tag`.
    pub fn node_index(&self, tag: u64) -> Option<u32> {
        self.node_tags.binary_search(&tag).ok().map(|i| i as u32)
    }

    /// Axis-aligned bounding box `[min, max]` of all nodes (zeros for an empty mesh).
    pub fn bbox(&self) -> [[f64; 3]; 2] {
        self.coords
            .par_chunks(1 << 16)
            .map(|c| bbox_of(c.iter()))
            .reduce_with(|a, b| {
                let mut out = a;
                for k in 0..3 {
                    out[0][k] = a[0][k].min(b[0][k]);
                    out[1][k] = a[1][k].max(b[1][k]);
                }
                out
            })
            .unwrap_or([[0.0; 3]; 2])
    }

    /// Length of the bounding box diagonal (m): the model size that relative tolerances refer to.
    pub fn size(&self) -> f64 {
        let [lo, hi] = self.bbox();
        ((hi[0] - lo[0]).powi(2) + (hi[1] - lo[1]).powi(2) + (hi[2] - lo[2]).powi(2)).sqrt()
    }
}

/// Bounding box of a set of points (zeros when empty).
pub fn bbox_of<'a>(points: impl Iterator<Item = &'a [f64; 3]>) -> [[f64; 3]; 2] {
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    let mut any = false;
    for p in points {
        any = true;
        for c in 0..3 {
            lo[c] = lo[c].min(p[c]);
            hi[c] = hi[c].max(p[c]);
        }
    }
    if any {
        [lo, hi]
    } else {
        [[0.0; 3]; 2]
    }
}

#[cfg(test)]
mod tests {
    use super::ElementTags;

    #[test]
    fn element_tags_keep_a_run_while_the_tags_run_on() {
        let mut t = ElementTags::default();
        assert!(t.is_empty());
        for k in 5..9 {
            t.push(k);
        }
        assert_eq!(t, ElementTags::Run { first: 5, len: 4 });
        assert_eq!((t.len(), t.at(0), t.at(3)), (4, 5, 8));
        t.push(20);
        assert_eq!(t, ElementTags::List(vec![5, 6, 7, 8, 20]));
        t.push(21);
        assert_eq!(t.iter().collect::<Vec<_>>(), vec![5, 6, 7, 8, 20, 21]);
        assert_eq!(t.at(4), 20);
        // From a vector and an iterator: the same representation for the same sequence.
        assert_eq!(
            ElementTags::from(vec![3, 4, 5]),
            ElementTags::Run { first: 3, len: 3 }
        );
        assert_eq!(ElementTags::from(vec![3, 5]), ElementTags::List(vec![3, 5]));
        assert_eq!(ElementTags::from(vec![]), ElementTags::default());
        assert_eq!(
            (1..=4).rev().collect::<ElementTags>(),
            ElementTags::from(vec![4, 3, 2, 1])
        );
        // Tags at the top of the range do not overflow.
        let top = ElementTags::from(vec![u64::MAX - 1, u64::MAX]);
        assert_eq!(top.iter().collect::<Vec<_>>(), vec![u64::MAX - 1, u64::MAX]);
        let mut over = top.clone();
        over.push(0);
        assert_eq!(
            over.iter().collect::<Vec<_>>(),
            vec![u64::MAX - 1, u64::MAX, 0]
        );
        // Extending: runs that continue merge, others append.
        let mut a = ElementTags::Run { first: 1, len: 3 };
        a.extend(&ElementTags::Run { first: 4, len: 2 });
        assert_eq!(a, ElementTags::Run { first: 1, len: 5 });
        a.extend(&ElementTags::Run { first: 10, len: 2 });
        assert_eq!(a.iter().collect::<Vec<_>>(), vec![1, 2, 3, 4, 5, 10, 11]);
        a.extend(&ElementTags::List(vec![7, 3]));
        assert_eq!(a.len(), 9);
        assert_eq!(a.at(8), 3);
        let mut empty = ElementTags::default();
        empty.extend(&ElementTags::List(vec![2, 9]));
        assert_eq!(empty, ElementTags::List(vec![2, 9]));
    }

    #[test]
    #[should_panic(expected = "element 3 of a block of 3")]
    fn a_tag_beyond_the_run_panics_as_indexing_does() {
        ElementTags::Run { first: 1, len: 3 }.at(3);
    }
}
