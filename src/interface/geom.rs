//! The rigid transforms that place a target surface (cyclic rotation, static misalignment); the
//! vector algebra is [`crate::vec3`].

use crate::case::Misalignment;
use crate::vec3::{add, mat_mul, mat_vec, rotation_about, sub};

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
