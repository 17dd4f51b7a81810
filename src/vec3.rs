//! Small 3-vector and 3×3-matrix helpers on plain arrays (`[f64; 3]`, row-major [`Mat3`]): the
//! one home of the vector algebra of the geometry code (cyclic symmetry, contact frames, SAMA
//! projection). Rotations about an axis are built with `nalgebra`.

/// A 3×3 matrix, row-major.
pub type Mat3 = [[f64; 3]; 3];

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
pub fn mat_vec(m: &Mat3, v: [f64; 3]) -> [f64; 3] {
    [dot(m[0], v), dot(m[1], v), dot(m[2], v)]
}

/// A·B.
pub fn mat_mul(a: &Mat3, b: &Mat3) -> Mat3 {
    let mut c = [[0.0; 3]; 3];
    for (i, row) in c.iter_mut().enumerate() {
        for (j, cij) in row.iter_mut().enumerate() {
            *cij = (0..3).map(|k| a[i][k] * b[k][j]).sum();
        }
    }
    c
}

/// Rotation matrix (row-major) by `angle` (rad) about the direction `axis` (right-hand rule).
pub fn rotation_about(axis: [f64; 3], angle: f64) -> Mat3 {
    let axis = nalgebra::Unit::new_normalize(nalgebra::Vector3::from(axis));
    let r = nalgebra::Rotation3::from_axis_angle(&axis, angle);
    let m = r.matrix();
    [
        [m[(0, 0)], m[(0, 1)], m[(0, 2)]],
        [m[(1, 0)], m[(1, 1)], m[(1, 2)]],
        [m[(2, 0)], m[(2, 1)], m[(2, 2)]],
    ]
}

/// Aᵀ.
pub fn transpose(a: &Mat3) -> Mat3 {
    let mut t = [[0.0; 3]; 3];
    for (i, row) in t.iter_mut().enumerate() {
        for (j, tij) in row.iter_mut().enumerate() {
            *tij = a[j][i];
        }
    }
    t
}

/// R (p − o) + o: the point `p` rotated by `r` about the point `origin`.
pub fn rotate_about(r: &Mat3, origin: [f64; 3], p: [f64; 3]) -> [f64; 3] {
    let v = mat_vec(r, sub(p, origin));
    [v[0] + origin[0], v[1] + origin[1], v[2] + origin[2]]
}
