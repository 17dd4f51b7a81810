//! Gmsh element types and their node orderings.
//!
//! nlrom keeps Gmsh's node ordering for every element (Gmsh reference manual, section "Node
//! ordering"). In short: corners first, in the order of the first-order element; then mid-edge
//! nodes in Gmsh's edge order; then mid-face nodes; then the interior node.
//!
//! | type | edges (mid-node order) |
//! |---|---|
//! | triangle6 | (0,1) (1,2) (2,0) |
//! | quad8/9 | (0,1) (1,2) (2,3) (3,0), quad9 adds the centre |
//! | tetra10 | (0,1) (1,2) (2,0) (3,0) (3,2) (3,1) — the last two differ from VTK/meshio |
//! | hexa20/27 | (0,1) (0,3) (0,4) (1,2) (1,5) (2,3) (2,6) (3,7) (4,5) (4,7) (5,6) (6,7); hexa27 adds 6 face centres and the body centre |
//! | prism15/18 | (0,1) (0,2) (0,3) (1,2) (1,4) (2,5) (3,4) (3,5) (4,5); prism18 adds 3 quad-face centres |
//! | pyramid13/14 | (0,1) (0,2) (0,3) (1,2) (1,4) (2,3) (2,4) (3,4); pyramid14 adds the base centre |

use std::fmt;

/// The element types nlrom reads, with their Gmsh type numbers.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum ElementType {
    Point,
    Line2,
    Line3,
    Triangle3,
    Triangle6,
    Quad4,
    Quad8,
    Quad9,
    Tetra4,
    Tetra10,
    Hexa8,
    Hexa20,
    Hexa27,
    Prism6,
    Prism15,
    Prism18,
    Pyramid5,
    Pyramid13,
    Pyramid14,
}

/// Every supported type, in Gmsh type-number order of first appearance.
pub const ALL_TYPES: [ElementType; 19] = [
    ElementType::Point,
    ElementType::Line2,
    ElementType::Line3,
    ElementType::Triangle3,
    ElementType::Triangle6,
    ElementType::Quad4,
    ElementType::Quad8,
    ElementType::Quad9,
    ElementType::Tetra4,
    ElementType::Tetra10,
    ElementType::Hexa8,
    ElementType::Hexa20,
    ElementType::Hexa27,
    ElementType::Prism6,
    ElementType::Prism15,
    ElementType::Prism18,
    ElementType::Pyramid5,
    ElementType::Pyramid13,
    ElementType::Pyramid14,
];

impl ElementType {
    /// The type for a Gmsh element type number, `None` for types nlrom does not read.
    pub fn from_gmsh(id: i64) -> Option<ElementType> {
        use ElementType::*;
        Some(match id {
            1 => Line2,
            2 => Triangle3,
            3 => Quad4,
            4 => Tetra4,
            5 => Hexa8,
            6 => Prism6,
            7 => Pyramid5,
            8 => Line3,
            9 => Triangle6,
            10 => Quad9,
            11 => Tetra10,
            12 => Hexa27,
            13 => Prism18,
            14 => Pyramid14,
            15 => Point,
            16 => Quad8,
            17 => Hexa20,
            18 => Prism15,
            19 => Pyramid13,
            _ => return None,
        })
    }

    /// The Gmsh element type number.
    pub fn gmsh_id(self) -> i32 {
        use ElementType::*;
        match self {
            Line2 => 1,
            Triangle3 => 2,
            Quad4 => 3,
            Tetra4 => 4,
            Hexa8 => 5,
            Prism6 => 6,
            Pyramid5 => 7,
            Line3 => 8,
            Triangle6 => 9,
            Quad9 => 10,
            Tetra10 => 11,
            Hexa27 => 12,
            Prism18 => 13,
            Pyramid14 => 14,
            Point => 15,
            Quad8 => 16,
            Hexa20 => 17,
            Prism15 => 18,
            Pyramid13 => 19,
        }
    }

    /// Number of nodes of one element.
    pub fn num_nodes(self) -> usize {
        use ElementType::*;
        match self {
            Point => 1,
            Line2 => 2,
            Line3 => 3,
            Triangle3 => 3,
            Triangle6 => 6,
            Quad4 => 4,
            Quad8 => 8,
            Quad9 => 9,
            Tetra4 => 4,
            Tetra10 => 10,
            Hexa8 => 8,
            Hexa20 => 20,
            Hexa27 => 27,
            Prism6 => 6,
            Prism15 => 15,
            Prism18 => 18,
            Pyramid5 => 5,
            Pyramid13 => 13,
            Pyramid14 => 14,
        }
    }

    /// Number of corner (first-order) nodes; they come first in Gmsh's ordering.
    pub fn num_corners(self) -> usize {
        self.first_order().num_nodes()
    }

    /// Topological dimension: 0 point, 1 line, 2 surface, 3 volume.
    pub fn dim(self) -> u8 {
        use ElementType::*;
        match self {
            Point => 0,
            Line2 | Line3 => 1,
            Triangle3 | Triangle6 | Quad4 | Quad8 | Quad9 => 2,
            _ => 3,
        }
    }

    /// Polynomial order of the geometry (0 for a point).
    pub fn order(self) -> u8 {
        use ElementType::*;
        match self {
            Point => 0,
            Line2 | Triangle3 | Quad4 | Tetra4 | Hexa8 | Prism6 | Pyramid5 => 1,
            _ => 2,
        }
    }

    /// The first-order type with the same shape.
    pub fn first_order(self) -> ElementType {
        use ElementType::*;
        match self {
            Line3 => Line2,
            Triangle6 => Triangle3,
            Quad8 | Quad9 => Quad4,
            Tetra10 => Tetra4,
            Hexa20 | Hexa27 => Hexa8,
            Prism15 | Prism18 => Prism6,
            Pyramid13 | Pyramid14 => Pyramid5,
            t => t,
        }
    }

    /// The name nlrom reports (`mesh info`), e.g. `tetra10`.
    pub fn name(self) -> &'static str {
        use ElementType::*;
        match self {
            Point => "point",
            Line2 => "line2",
            Line3 => "line3",
            Triangle3 => "triangle3",
            Triangle6 => "triangle6",
            Quad4 => "quad4",
            Quad8 => "quad8",
            Quad9 => "quad9",
            Tetra4 => "tetra4",
            Tetra10 => "tetra10",
            Hexa8 => "hexa8",
            Hexa20 => "hexa20",
            Hexa27 => "hexa27",
            Prism6 => "prism6",
            Prism15 => "prism15",
            Prism18 => "prism18",
            Pyramid5 => "pyramid5",
            Pyramid13 => "pyramid13",
            Pyramid14 => "pyramid14",
        }
    }

    /// The faces of a volume element as local node lists in Gmsh order, each oriented with its
    /// normal pointing out of the element (right-hand rule on the corners), and typed as the
    /// surface element Gmsh would write for it (e.g. a tetra10 face is a triangle6). Empty for
    /// elements that are not volumes.
    pub fn faces(self) -> Vec<(ElementType, Vec<usize>)> {
        use ElementType::*;
        let tri = |o: u8| if o == 1 { Triangle3 } else { Triangle6 };
        match self {
            Tetra4 | Tetra10 => {
                // Corners (0,2,1), (0,1,3), (0,3,2), (1,2,3): outward for a positively oriented tet.
                let quad = self == Tetra10;
                let faces: [([usize; 3], [usize; 3]); 4] = [
                    ([0, 2, 1], [6, 5, 4]),
                    ([0, 1, 3], [4, 9, 7]),
                    ([0, 3, 2], [7, 8, 6]),
                    ([1, 2, 3], [5, 8, 9]),
                ];
                faces
                    .iter()
                    .map(|(c, m)| {
                        let mut v = c.to_vec();
                        if quad {
                            v.extend_from_slice(m);
                        }
                        (tri(self.order()), v)
                    })
                    .collect()
            }
            Hexa8 | Hexa20 | Hexa27 => {
                // Gmsh hexa edges: e8=(0,1) e9=(0,3) e10=(0,4) e11=(1,2) e12=(1,5) e13=(2,3)
                // e14=(2,6) e15=(3,7) e16=(4,5) e17=(4,7) e18=(5,6) e19=(6,7); face centres 20..25
                // in the order of the faces below; body centre 26.
                let faces: [([usize; 4], [usize; 4], usize); 6] = [
                    ([0, 3, 2, 1], [9, 13, 11, 8], 20),
                    ([0, 1, 5, 4], [8, 12, 16, 10], 21),
                    ([0, 4, 7, 3], [10, 17, 15, 9], 22),
                    ([1, 2, 6, 5], [11, 14, 18, 12], 23),
                    ([2, 3, 7, 6], [13, 15, 19, 14], 24),
                    ([4, 5, 6, 7], [16, 18, 19, 17], 25),
                ];
                faces
                    .iter()
                    .map(|(c, m, centre)| face_of(self, c, m, Some(*centre)))
                    .collect()
            }
            Prism6 | Prism15 | Prism18 => {
                // Gmsh prism edges: e6=(0,1) e7=(0,2) e8=(0,3) e9=(1,2) e10=(1,4) e11=(2,5)
                // e12=(3,4) e13=(3,5) e14=(4,5); quad-face centres 15, 16, 17.
                let tris: [([usize; 3], [usize; 3]); 2] =
                    [([0, 2, 1], [7, 9, 6]), ([3, 4, 5], [12, 14, 13])];
                let quads: [([usize; 4], [usize; 4], usize); 3] = [
                    ([0, 1, 4, 3], [6, 10, 12, 8], 15),
                    ([0, 3, 5, 2], [8, 13, 11, 7], 16),
                    ([1, 2, 5, 4], [9, 11, 14, 10], 17),
                ];
                let mut out: Vec<(ElementType, Vec<usize>)> = tris
                    .iter()
                    .map(|(c, m)| {
                        let mut v = c.to_vec();
                        if self != Prism6 {
                            v.extend_from_slice(m);
                        }
                        (tri(self.order()), v)
                    })
                    .collect();
                out.extend(
                    quads
                        .iter()
                        .map(|(c, m, centre)| face_of(self, c, m, Some(*centre))),
                );
                out
            }
            Pyramid5 | Pyramid13 | Pyramid14 => {
                // Gmsh pyramid edges: (0,1) (0,3) (0,4) (1,2) (1,4) (2,3) (2,4) (3,4) -> nodes
                // 5..12; base centre 13.
                let base = face_of(self, &[0, 3, 2, 1], &[6, 10, 8, 5], Some(13));
                let tris: [([usize; 3], [usize; 3]); 4] = [
                    ([0, 1, 4], [5, 9, 7]),
                    ([1, 2, 4], [8, 11, 9]),
                    ([2, 3, 4], [10, 12, 11]),
                    ([3, 0, 4], [6, 7, 12]),
                ];
                let mut out = vec![base];
                out.extend(tris.iter().map(|(c, m)| {
                    let mut v = c.to_vec();
                    if self != Pyramid5 {
                        v.extend_from_slice(m);
                    }
                    (tri(self.order()), v)
                }));
                out
            }
            _ => Vec::new(),
        }
    }
}

/// A quadrilateral face of `vol` from its corners, mid-edge nodes and centre.
fn face_of(
    vol: ElementType,
    corners: &[usize; 4],
    mids: &[usize; 4],
    centre: Option<usize>,
) -> (ElementType, Vec<usize>) {
    use ElementType::*;
    let mut v = corners.to_vec();
    match vol {
        Hexa8 | Prism6 | Pyramid5 => (Quad4, v),
        Hexa20 | Prism15 | Pyramid13 => {
            v.extend_from_slice(mids);
            (Quad8, v)
        }
        _ => {
            v.extend_from_slice(mids);
            v.extend(centre);
            (Quad9, v)
        }
    }
}

impl fmt::Display for ElementType {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}
