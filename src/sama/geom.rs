//! Small 3-vector and 3×3-matrix helpers on plain arrays (row-major matrices), and the rigid
//! transforms that place a target surface (cyclic rotation, static misalignment).

use crate::case::Misalignment;

/// a − b.
pub fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

/// a + b.
pub fn add(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}

/// s·a.
pub fn scale(s: f64, a: [f64; 3]) -> [f64; 3] {
    [s * a[0], s * a[1], s * a[2]]
}

/// a·b.
pub fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// a × b.
pub fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

/// |a|.
pub fn norm(a: [f64; 3]) -> f64 {
    dot(a, a).sqrt()
}

/// a/|a| (a must not be zero).
pub fn unit(a: [f64; 3]) -> [f64; 3] {
    scale(1.0 / norm(a), a)
}

/// M·v for a row-major 3×3 matrix.
pub fn mat_vec(m: &[[f64; 3]; 3], v: [f64; 3]) -> [f64; 3] {
    [dot(m[0], v), dot(m[1], v), dot(m[2], v)]
}

/// A·B.
pub fn mat_mul(a: &[[f64; 3]; 3], b: &[[f64; 3]; 3]) -> [[f64; 3]; 3] {
    let mut c = [[0.0; 3]; 3];
    for (i, row) in c.iter_mut().enumerate() {
        for (j, cij) in row.iter_mut().enumerate() {
            *cij = (0..3).map(|k| a[i][k] * b[k][j]).sum();
        }
    }
    c
}

/// Rotation matrix (row-major) by `angle` (rad) about the direction `axis` (right-hand rule).
pub fn rotation_about(axis: [f64; 3], angle: f64) -> [[f64; 3]; 3] {
    let axis = nalgebra::Unit::new_normalize(nalgebra::Vector3::from(axis));
    let r = nalgebra::Rotation3::from_axis_angle(&axis, angle);
    let m = r.matrix();
    [
        [m[(0, 0)], m[(0, 1)], m[(0, 2)]],
        [m[(1, 0)], m[(1, 1)], m[(1, 2)]],
        [m[(2, 0)], m[(2, 1)], m[(2, 2)]],
    ]
}

/// A rigid placement x ↦ R (x − o) + o + t.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RigidMap {
    /// Rotation R (row-major).
    pub rotation: [[f64; 3]; 3],
    /// Centre of the rotation o (m).
    pub origin: [f64; 3],
    /// Translation t (m), applied after the rotation.
    pub translation: [f64; 3],
}

impl RigidMap {
    /// The identity.
    pub fn identity() -> Self {
        RigidMap {
            rotation: [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
            origin: [0.0; 3],
            translation: [0.0; 3],
        }
    }

    /// A pure rotation R about the line through `origin`.
    pub fn rotation(rotation: [[f64; 3]; 3], origin: [f64; 3]) -> Self {
        RigidMap {
            rotation,
            origin,
            translation: [0.0; 3],
        }
    }

    /// The static misalignment of a `[[contact]]` (case::Misalignment): rotation by `angle_deg`
    /// about `rotate.axis` through `rotate.origin` first, then the translation `translate`.
    pub fn misalignment(m: &Misalignment) -> Self {
        let mut map = RigidMap::identity();
        if let Some(r) = &m.rotate {
            map.rotation = rotation_about(r.axis, r.angle_deg.to_radians());
            map.origin = r.origin;
        }
        map.translation = m.translate;
        map
    }

    /// The image of the point `x`.
    pub fn apply(&self, x: [f64; 3]) -> [f64; 3] {
        add(
            add(mat_vec(&self.rotation, sub(x, self.origin)), self.origin),
            self.translation,
        )
    }

    /// `self ∘ first`: apply `first`, then `self`.
    pub fn after(&self, first: &RigidMap) -> RigidMap {
        // self(first(x)) = R2 (R1 (x − o1) + o1 + t1 − o2) + o2 + t2
        //               = R2 R1 (x − o1) + o1 + [R2 (o1 + t1 − o2) + o2 + t2 − o1]
        let o1 = first.origin;
        let shifted = mat_vec(&self.rotation, sub(add(o1, first.translation), self.origin));
        RigidMap {
            rotation: mat_mul(&self.rotation, &first.rotation),
            origin: o1,
            translation: sub(add(add(shifted, self.origin), self.translation), o1),
        }
    }
}
