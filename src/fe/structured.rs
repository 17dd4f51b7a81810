//! Structured box meshes built in memory, for tests and benchmarks.
//!
//! A box [x₀, x₀ + Lx] × [y₀, y₀ + Ly] × [z₀, z₀ + Lz] is divided into nx × ny × nz cells. Each
//! cell becomes one hexahedron (hexa8/20/27), two prisms (prism6/15/18: the cell's xy face split
//! along its (0,0)–(1,1) diagonal and extruded along z), six tetrahedra (tetra4/10: the Kuhn
//! split along the cell's main diagonal, conforming between cells) or three pyramids
//! (pyramid5/13: the apex at the cell's vertex whose grid indices are all odd, the bases the three
//! faces away from it; neighbouring cells then share either a whole base or the same two
//! triangles, so the mesh is conforming). Higher-order nodes are the mid-points of straight edges
//! (and face/body centres for hexa27/prism18), so every element is straight-sided and the box
//! volume is exact.
//!
//! Optionally the interior vertices are moved by a deterministic pseudo-random amount (each
//! coordinate by up to `distortion` × the cell size) while the boundary stays flat: a distorted
//! mesh for patch tests, with higher-order nodes still at the mid-points of the moved edges.
//!
//! The mesh has the physical groups `volume` (dim 3, tag 1) and the six faces `xmin`, `xmax`,
//! `ymin`, `ymax`, `zmin`, `zmax` (dim 2, tags 2..7) as surface elements (triangles or quads of
//! the matching order, oriented outward; a pyramid box has both triangles and quadrilaterals on
//! a face, one block of each), so `Mesh::group_node_indices` and `faces::group_faces`
//! work on them. Node tags are 1.. in ascending grid order (x fastest), element tags 1.. (volume
//! elements first).

use std::path::PathBuf;

use crate::error::{Error, Result};
use crate::mesh::{
    ElementBlock, ElementTags, ElementType, Mesh, MshFormat, MshVersion, PhysicalGroup,
};

use super::shape::node_parents;

/// The names of the six face groups, in tag order 2..7.
pub const FACE_GROUPS: [&str; 6] = ["xmin", "xmax", "ymin", "ymax", "zmin", "zmax"];

/// A structured box mesh specification; [`StructuredBox::build`] makes the [`Mesh`].
#[derive(Clone, Debug, PartialEq)]
pub struct StructuredBox {
    /// Element type: tetra4/10, hexa8/20/27, prism6/15/18 or pyramid5/13.
    pub kind: ElementType,
    /// Number of cells along x, y, z (each ≥ 1).
    pub cells: [usize; 3],
    /// Box edge lengths Lx, Ly, Lz (m), > 0.
    pub size: [f64; 3],
    /// The corner with the smallest coordinates (m).
    pub origin: [f64; 3],
    /// Interior vertex displacement amplitude as a fraction of the cell size, in [0, 0.25]; 0 is a
    /// regular grid.
    pub distortion: f64,
    /// Seed of the deterministic displacement.
    pub seed: u64,
}

/// Cube corner offsets in Gmsh hexahedron order.
const CUBE: [[usize; 3]; 8] = [
    [0, 0, 0],
    [1, 0, 0],
    [1, 1, 0],
    [0, 1, 0],
    [0, 0, 1],
    [1, 0, 1],
    [1, 1, 1],
    [0, 1, 1],
];

/// The six Kuhn tetrahedra of a cube (paths from corner 0 to corner 6), before orientation.
const KUHN: [[usize; 4]; 6] = [
    [0, 1, 2, 6],
    [0, 2, 3, 6],
    [0, 3, 7, 6],
    [0, 7, 4, 6],
    [0, 4, 5, 6],
    [0, 5, 1, 6],
];

/// The two prisms of a cube (bottom triangle corners, then the top ones).
const PRISMS: [[usize; 6]; 2] = [[0, 1, 2, 4, 5, 6], [0, 2, 3, 4, 6, 7]];

impl StructuredBox {
    /// A regular box of `cells` cells of `kind` with edge lengths `size`, origin at 0.
    pub fn new(kind: ElementType, cells: [usize; 3], size: [f64; 3]) -> Self {
        StructuredBox {
            kind,
            cells,
            size,
            origin: [0.0; 3],
            distortion: 0.0,
            seed: 1,
        }
    }

    /// The same box with its interior vertices displaced (see the module documentation).
    pub fn distorted(mut self, distortion: f64, seed: u64) -> Self {
        self.distortion = distortion;
        self.seed = seed;
        self
    }

    /// Builds the mesh. Errors ([`Error::Input`]) for an unsupported type, zero cells, a
    /// non-positive size or a distortion outside [0, 0.25].
    pub fn build(&self) -> Result<Mesh> {
        self.validate()?;
        let grid = Grid::new(self);
        let mut nodes = NodeSet::new(&grid);
        let mut volume: Vec<usize> = Vec::new();
        for cell in grid.cells() {
            for corners in self.cell_elements(cell) {
                nodes.add_element(&grid, self.kind, &corners, &mut volume);
            }
        }
        Ok(nodes.into_mesh(&grid, self, &volume))
    }

    fn validate(&self) -> Result<()> {
        use ElementType::*;
        if !matches!(
            self.kind,
            Tetra4
                | Tetra10
                | Hexa8
                | Hexa20
                | Hexa27
                | Prism6
                | Prism15
                | Prism18
                | Pyramid5
                | Pyramid13
        ) {
            return Err(Error::input(format!(
                "structured box: {} elements are not generated; use tetra4/10, hexa8/20/27, prism6/15/18 or pyramid5/13",
                self.kind
            )));
        }
        if self.cells.contains(&0) {
            return Err(Error::input(format!(
                "structured box: cells = {:?} must all be ≥ 1",
                self.cells
            )));
        }
        if !self.size.iter().all(|&s| s.is_finite() && s > 0.0)
            || !self.origin.iter().all(|o| o.is_finite())
        {
            return Err(Error::input(format!(
                "structured box: size = {:?} must be positive and origin = {:?} finite",
                self.size, self.origin
            )));
        }
        if !(0.0..=0.25).contains(&self.distortion) {
            return Err(Error::input(format!(
                "structured box: distortion = {} must be in [0, 0.25] (larger moves can invert elements)",
                self.distortion
            )));
        }
        Ok(())
    }

    /// The elements of the cell with lowest vertex `cell`, as doubled-grid corner coordinates in
    /// Gmsh corner order, positively oriented.
    fn cell_elements(&self, cell: [usize; 3]) -> Vec<Vec<[usize; 3]>> {
        let at = |c: usize| {
            let o = CUBE[c];
            [
                2 * (cell[0] + o[0]),
                2 * (cell[1] + o[1]),
                2 * (cell[2] + o[2]),
            ]
        };
        match self.kind.first_order() {
            ElementType::Hexa8 => vec![(0..8).map(at).collect()],
            ElementType::Prism6 => PRISMS
                .iter()
                .map(|p| p.iter().map(|&c| at(c)).collect())
                .collect(),
            ElementType::Pyramid5 => {
                // The bases: the cube faces away from the apex (`CUBE` is in Gmsh hexahedron
                // order, whose faces are outward), reversed to face the apex.
                let apex = pyramid_apex(cell);
                ElementType::Hexa8
                    .faces()
                    .into_iter()
                    .filter(|(_, f)| !f.contains(&apex))
                    .map(|(_, f)| f.iter().rev().chain([&apex]).map(|&c| at(c)).collect())
                    .collect()
            }
            _ => KUHN
                .iter()
                .map(|t| {
                    let mut t = *t;
                    if tet_sign(t) < 0.0 {
                        t.swap(1, 2);
                    }
                    t.iter().map(|&c| at(c)).collect()
                })
                .collect(),
        }
    }
}

/// The corner of cell `cell` (index into `CUBE`) whose vertex has odd grid indices in every
/// direction: the apex of the cell's three pyramids. Cells sharing a face then agree on it.
fn pyramid_apex(cell: [usize; 3]) -> usize {
    let odd = cell.map(|i| usize::from(i % 2 == 0));
    CUBE.iter()
        .position(|&o| o == odd)
        .expect("every offset triple is a cube corner")
}

/// Sign of the volume of the tetrahedron with these cube corners.
fn tet_sign(t: [usize; 4]) -> f64 {
    let p = |c: usize| CUBE[t[c]].map(|v| v as f64);
    let (a, b, c, d) = (p(0), p(1), p(2), p(3));
    let u = [b[0] - a[0], b[1] - a[1], b[2] - a[2]];
    let v = [c[0] - a[0], c[1] - a[1], c[2] - a[2]];
    let w = [d[0] - a[0], d[1] - a[1], d[2] - a[2]];
    u[0] * (v[1] * w[2] - v[2] * w[1]) - u[1] * (v[0] * w[2] - v[2] * w[0])
        + u[2] * (v[0] * w[1] - v[1] * w[0])
}

/// The doubled grid: points (i, j, k) with 0 ≤ i ≤ 2nx etc.; even coordinates are cell vertices.
struct Grid {
    cells: [usize; 3],
    dims: [usize; 3],
    origin: [f64; 3],
    step: [f64; 3],
    distortion: f64,
    seed: u64,
}

impl Grid {
    fn new(b: &StructuredBox) -> Grid {
        Grid {
            cells: b.cells,
            dims: b.cells.map(|n| 2 * n + 1),
            origin: b.origin,
            step: [0, 1, 2].map(|k| b.size[k] / b.cells[k] as f64),
            distortion: b.distortion,
            seed: b.seed,
        }
    }

    fn cells(&self) -> impl Iterator<Item = [usize; 3]> + '_ {
        let [nx, ny, nz] = self.cells;
        (0..nz).flat_map(move |k| (0..ny).flat_map(move |j| (0..nx).map(move |i| [i, j, k])))
    }

    /// Linear index of a doubled-grid point (x fastest).
    fn key(&self, p: [usize; 3]) -> usize {
        p[0] + self.dims[0] * (p[1] + self.dims[1] * p[2])
    }

    /// Position of the vertex at doubled coordinates `p` (all even), displaced if interior.
    fn vertex(&self, p: [usize; 3]) -> [f64; 3] {
        let interior = (0..3).all(|k| p[k] > 0 && p[k] < self.dims[k] - 1);
        let mut x = [0.0; 3];
        for k in 0..3 {
            x[k] = self.origin[k] + (p[k] / 2) as f64 * self.step[k];
            if interior && self.distortion > 0.0 {
                let h = splitmix64(self.seed ^ splitmix64((self.key(p) * 3 + k) as u64));
                let unit = (h >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0;
                x[k] += self.distortion * self.step[k] * unit;
            }
        }
        x
    }

    /// Index of the face group (0..6) that all points `ps` lie on, if any (first match).
    fn boundary(&self, ps: &[[usize; 3]]) -> Option<usize> {
        (0..3).find_map(|k| {
            if ps.iter().all(|p| p[k] == 0) {
                Some(2 * k)
            } else if ps.iter().all(|p| p[k] == self.dims[k] - 1) {
                Some(2 * k + 1)
            } else {
                None
            }
        })
    }
}

/// SplitMix64: a well-mixed 64-bit hash, for deterministic pseudo-random displacements.
fn splitmix64(x: u64) -> u64 {
    let mut z = x.wrapping_add(0x9e37_79b9_7f4a_7c15);
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

/// The nodes used so far (by grid key) and the boundary faces found.
struct NodeSet {
    /// Position of each used grid point (`None` if unused).
    positions: Vec<Option<[f64; 3]>>,
    /// Boundary faces per face group: (face type, grid keys in Gmsh order).
    faces: [Vec<(ElementType, Vec<usize>)>; 6],
}

impl NodeSet {
    fn new(grid: &Grid) -> NodeSet {
        NodeSet {
            positions: vec![None; grid.dims.iter().product()],
            faces: Default::default(),
        }
    }

    /// Adds the element with corners `corners` (doubled coordinates): its node keys go to
    /// `volume`, its boundary faces to `faces`.
    fn add_element(
        &mut self,
        grid: &Grid,
        kind: ElementType,
        corners: &[[usize; 3]],
        volume: &mut Vec<usize>,
    ) {
        let parents = node_parents(kind).unwrap_or_default();
        let corner_pos: Vec<[f64; 3]> = corners.iter().map(|&p| grid.vertex(p)).collect();
        let mut points = Vec::with_capacity(parents.len());
        let first = volume.len();
        for par in &parents {
            let mut p = [0usize; 3];
            let mut x = [0.0; 3];
            for &c in par {
                for k in 0..3 {
                    p[k] += corners[c][k];
                    x[k] += corner_pos[c][k] / par.len() as f64;
                }
            }
            let p = p.map(|v| v / par.len());
            let key = grid.key(p);
            self.positions[key].get_or_insert(x);
            volume.push(key);
            points.push(p);
        }
        for (face_kind, local) in kind.faces() {
            let fc: Vec<[usize; 3]> = local[..face_kind.num_corners()]
                .iter()
                .map(|&l| points[l])
                .collect();
            if let Some(g) = grid.boundary(&fc) {
                let keys = local.iter().map(|&l| volume[first + l]).collect();
                self.faces[g].push((face_kind, keys));
            }
        }
    }

    /// The mesh: nodes compacted in ascending key order, one volume block, one block per face group.
    fn into_mesh(self, grid: &Grid, spec: &StructuredBox, volume: &[usize]) -> Mesh {
        let mut index = vec![u32::MAX; self.positions.len()];
        let mut coords = Vec::new();
        for (key, pos) in self.positions.iter().enumerate() {
            if let Some(x) = pos {
                index[key] = coords.len() as u32;
                coords.push(*x);
            }
        }
        let n_vol = volume.len() / spec.kind.num_nodes();
        let mut blocks = vec![ElementBlock {
            kind: spec.kind,
            entity: 1,
            physicals: vec![1],
            tags: ElementTags::Run {
                first: 1,
                len: n_vol,
            },
            connectivity: volume.iter().map(|&k| index[k]).collect(),
        }];
        let mut next_tag = n_vol as u64 + 1;
        for (g, faces) in self.faces.iter().enumerate() {
            let mut kinds: Vec<ElementType> = faces.iter().map(|(kind, _)| *kind).collect();
            kinds.sort_by_key(|k| k.num_nodes());
            kinds.dedup();
            for face_kind in kinds {
                let of_kind: Vec<&Vec<usize>> = faces
                    .iter()
                    .filter(|(kind, _)| *kind == face_kind)
                    .map(|(_, keys)| keys)
                    .collect();
                let tags = ElementTags::Run {
                    first: next_tag,
                    len: of_kind.len(),
                };
                next_tag += of_kind.len() as u64;
                blocks.push(ElementBlock {
                    kind: face_kind,
                    entity: g as i32 + 1,
                    physicals: vec![g as i32 + 2],
                    tags,
                    connectivity: of_kind
                        .iter()
                        .flat_map(|keys| keys.iter().map(|&k| index[k]))
                        .collect(),
                });
            }
        }
        let mut groups = vec![PhysicalGroup {
            name: "volume".into(),
            dim: 3,
            tag: 1,
        }];
        groups.extend(
            FACE_GROUPS
                .iter()
                .enumerate()
                .map(|(g, name)| PhysicalGroup {
                    name: (*name).into(),
                    dim: 2,
                    tag: g as i32 + 2,
                }),
        );
        let [nx, ny, nz] = grid.cells;
        Mesh {
            source: Some(PathBuf::from(format!(
                "<structured {} box {nx}x{ny}x{nz}>",
                spec.kind
            ))),
            format: MshFormat {
                version: MshVersion::V41,
                binary: false,
                big_endian: false,
            },
            node_tags: (1..=coords.len() as u64).collect(),
            coords,
            blocks,
            groups,
            periodic: Vec::new(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn node_and_element_counts() {
        // (kind, elements per cell, nodes for 2×3×4 cells)
        let (nx, ny, nz) = (2, 3, 4);
        let v = (nx + 1) * (ny + 1) * (nz + 1);
        let ex = nx * (ny + 1) * (nz + 1) + (nx + 1) * ny * (nz + 1) + (nx + 1) * (ny + 1) * nz;
        let fxy = nx * ny * (nz + 1);
        let fxz = nx * (ny + 1) * nz;
        let fyz = (nx + 1) * ny * nz;
        let cells = nx * ny * nz;
        let cases = [
            (ElementType::Hexa8, 1, v),
            (ElementType::Hexa20, 1, v + ex),
            (
                ElementType::Hexa27,
                1,
                (2 * nx + 1) * (2 * ny + 1) * (2 * nz + 1),
            ),
            (ElementType::Prism6, 2, v),
            // + one xy-face diagonal per xy face
            (ElementType::Prism15, 2, v + ex + fxy),
            // Kuhn: + one diagonal per face of every orientation + one body diagonal per cell
            (ElementType::Tetra10, 6, v + ex + fxy + fxz + fyz + cells),
        ];
        for (kind, per_cell, nodes) in cases {
            let m = StructuredBox::new(kind, [nx, ny, nz], [1.0, 1.0, 1.0])
                .build()
                .unwrap();
            assert_eq!(m.num_nodes(), nodes, "{kind} nodes");
            assert_eq!(m.blocks[0].len(), per_cell * cells, "{kind} elements");
            let xmin = m.nodes_of("xmin").unwrap();
            assert!(
                xmin.iter().all(|&i| m.coords[i as usize][0] == 0.0),
                "{kind} xmin"
            );
            let zmax = m.nodes_of("zmax").unwrap();
            assert!(
                zmax.iter().all(|&i| m.coords[i as usize][2] == 1.0),
                "{kind} zmax"
            );
        }
    }

    #[test]
    fn boundary_faces_are_outward_faces_of_volume_elements() {
        use crate::mesh::faces::{area_vector, group_faces};
        for kind in [
            ElementType::Tetra10,
            ElementType::Hexa20,
            ElementType::Prism6,
            ElementType::Pyramid13,
        ] {
            let m = StructuredBox::new(kind, [2, 2, 2], [1.0, 2.0, 3.0])
                .distorted(0.2, 7)
                .build()
                .unwrap();
            for (g, name) in FACE_GROUPS.iter().enumerate() {
                let faces = group_faces(&m, name).unwrap();
                let area: f64 = faces
                    .iter()
                    .map(|f| {
                        let xs: Vec<[f64; 3]> =
                            f.nodes.iter().map(|&i| m.coords[i as usize]).collect();
                        crate::mesh::faces::face_area(f.kind, &xs)
                    })
                    .sum();
                let sizes = [1.0, 2.0, 3.0];
                let expected = sizes[(g / 2 + 1) % 3] * sizes[(g / 2 + 2) % 3];
                assert!((area - expected).abs() < 1e-12, "{kind} {name}: {area}");
                // Outward normal: the sign of the face normal's component along the axis.
                let f = &faces[0];
                let xs: Vec<[f64; 3]> = f.nodes.iter().map(|&i| m.coords[i as usize]).collect();
                let (u, v) = if f.kind.first_order() == ElementType::Triangle3 {
                    (1.0 / 3.0, 1.0 / 3.0)
                } else {
                    (0.0, 0.0)
                };
                let n = area_vector(f.kind, &xs, u, v);
                let sign = if g % 2 == 0 { -1.0 } else { 1.0 };
                assert!(n[g / 2] * sign > 0.0, "{kind} {name} orientation");
            }
        }
    }

    #[test]
    fn pyramid_boxes_are_conforming_and_fill_the_box() {
        // Every face of a volume element is shared by exactly two elements or lies on the box
        // boundary (one of the face groups), with all its nodes (mid-edge ones included); the
        // element volumes add up to the box's.
        use std::collections::HashMap;
        let size = [1.0, 2.0, 3.0];
        for kind in [ElementType::Pyramid5, ElementType::Pyramid13] {
            let spec = StructuredBox::new(kind, [3, 2, 3], size).distorted(0.2, 5);
            let m = spec.build().unwrap();
            assert_eq!(m.blocks[0].len(), 3 * 18, "{kind}");
            let mut count: HashMap<Vec<u32>, usize> = HashMap::new();
            for element in m.blocks[0].elements() {
                for (_, local) in kind.faces() {
                    let mut key: Vec<u32> = local.iter().map(|&l| element[l]).collect();
                    key.sort_unstable();
                    *count.entry(key).or_default() += 1;
                }
            }
            let mut boundary: Vec<Vec<u32>> = Vec::new();
            for block in &m.blocks[1..] {
                for face in block.elements() {
                    let mut key = face.to_vec();
                    key.sort_unstable();
                    boundary.push(key);
                }
            }
            for (key, n) in &count {
                let on_boundary = boundary.contains(key);
                assert_eq!(*n, if on_boundary { 1 } else { 2 }, "{kind}: face {key:?}");
            }
            assert_eq!(
                count.values().filter(|&&n| n == 1).count(),
                boundary.len(),
                "{kind}"
            );
            let volume = crate::fe::mesh_volume(&m, &crate::fe::Quadrature::default()).unwrap();
            assert!((volume - 6.0).abs() < 1e-12, "{kind}: {volume}");
        }
    }

    #[test]
    fn bad_specifications_are_errors() {
        let ok = StructuredBox::new(ElementType::Hexa8, [1, 1, 1], [1.0; 3]);
        assert!(StructuredBox {
            cells: [1, 0, 1],
            ..ok.clone()
        }
        .build()
        .is_err());
        assert!(StructuredBox {
            size: [1.0, -1.0, 1.0],
            ..ok.clone()
        }
        .build()
        .is_err());
        assert!(ok.clone().distorted(0.5, 1).build().is_err());
        let e = StructuredBox {
            kind: ElementType::Pyramid14,
            ..ok
        }
        .build()
        .unwrap_err()
        .to_string();
        assert!(e.contains("pyramid14"), "{e}");
    }
}
