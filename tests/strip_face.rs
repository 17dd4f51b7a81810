//! `[[strip]]` on a mesh face group (`face`, `direction`): the contact area of Cigeroglu, An &
//! Menq (2007, §2, eq 38) as the Gauss points of the faces of a Gmsh surface group, against
//! references that do not use that construction:
//! * the consistent surface matrix ∫ N_a N_b dA of every face, in closed form for flat
//!   quadrilaterals (A/36 [4 2 1 2; …]) and triangles (A/12 [2 1 1; …]), with the faces' normals
//!   and the projected slip direction;
//! * the line strip of the same length, width and load, built by hand on the nodes of the bar
//!   damper mesh (`meshes/damper_bar.msh`, made by `tools/meshes/make_meshes.py`): the face
//!   points at each position add up to the line strip's point there (stiffness, preload and
//!   DOF weights, 1e-12);
//! * the forced response and the stick–slip maps of that mesh case with the face strip equal
//!   those with the hand-built line strip (the bar and its load are symmetric about both
//!   mid-planes, so every face point at a position moves as the line point there);
//! * keyed errors for a face strip given wrongly.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use nlrom::case::{Case, FrictionElement};
use nlrom::mesh::msh::read_msh;
use nlrom::mesh::Mesh;
use nlrom::model::{self, StructuralModel};
use nlrom::problem::face_strip::face_points;
use nlrom::problem::matrix_case::strip_points;

#[path = "support/face_bar.rs"]
mod face_bar;
use face_bar::{agreement, case_text, solve};

/// The bar damper: length, side, elements along x.
const L: f64 = 1.25;
const A: f64 = 0.01;
const NX: usize = 40;

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn mesh(name: &str) -> Mesh {
    read_msh(&root().join("meshes").join(name)).unwrap()
}

/// Flat faces: every face's ∫ N_a N_b dA (by the strip's points, g = 2) equals the closed form
/// of a parallelogram (A/36: 4 on the diagonal, 2 for neighbouring corners, 1 for opposite ones)
/// or a triangle (A/12: 2 on the diagonal, 1 off it) to 1e-12 of A; the areas add up to the
/// group's (1e-12); the normals point out of the volume and the slip direction is projected on
/// the face's plane.
#[test]
fn face_points_integrate_the_consistent_surface_matrix() {
    let cases: [(&str, &str, [f64; 3], f64); 3] = [
        ("damper_bar.msh", "pads", [1.0, 0.0, 0.0], 2.0 * L * A),
        ("damper_bar.msh", "pads", [2.0, 2.0, 1.0], 2.0 * L * A),
        ("cube_tet4.msh", "bottom", [0.0, 3.0, 0.0], 1.0),
    ];
    for (file, group, direction, total) in cases {
        let m = mesh(file);
        let fp = face_points(&m, group, direction, 2).unwrap();
        let mut faces: BTreeMap<u64, Vec<usize>> = BTreeMap::new();
        for (i, p) in fp.points.iter().enumerate() {
            faces.entry(p.surface_tag).or_default().push(i);
        }
        let mut area_sum = 0.0;
        let mut worst: f64 = 0.0;
        for points in faces.values() {
            let nodes: Vec<u32> = fp.points[points[0]].nodes.iter().map(|n| n.0).collect();
            let x = |k: usize| m.coords[nodes[k] as usize];
            let d = |a: usize, b: usize| {
                let (p, q) = (x(a), x(b));
                [q[0] - p[0], q[1] - p[1], q[2] - p[2]]
            };
            let cross = |u: [f64; 3], v: [f64; 3]| {
                [
                    u[1] * v[2] - u[2] * v[1],
                    u[2] * v[0] - u[0] * v[2],
                    u[0] * v[1] - u[1] * v[0],
                ]
            };
            let nn = nodes.len();
            let av = if nn == 4 {
                cross(d(0, 1), d(0, 3))
            } else {
                cross(d(0, 1), d(0, 2)).map(|c| 0.5 * c)
            };
            let area = (av[0] * av[0] + av[1] * av[1] + av[2] * av[2]).sqrt();
            area_sum += area;
            let closed = |a: usize, b: usize| -> f64 {
                if nn == 4 {
                    let k = (a + 4 - b) % 4;
                    area / 36.0 * [4.0, 2.0, 1.0, 2.0][k]
                } else {
                    area / 12.0 * if a == b { 2.0 } else { 1.0 }
                }
            };
            let unit_normal = av.map(|c| c / area);
            for a in 0..nn {
                for b in 0..nn {
                    let quad: f64 = points
                        .iter()
                        .map(|&i| {
                            let p = &fp.points[i];
                            p.area * p.nodes[a].1 * p.nodes[b].1
                        })
                        .sum();
                    worst = worst.max((quad - closed(a, b)).abs() / area);
                }
            }
            // the volume lies on the side opposite to the normal
            let centre = if file.starts_with("damper") {
                [0.5 * L, 0.5 * A, 0.5 * A]
            } else {
                [0.5; 3]
            };
            for &i in points {
                let p = &fp.points[i];
                for (n, u) in p.normal.iter().zip(&unit_normal) {
                    assert!((n - u).abs() < 1e-12, "{file} normal");
                }
                let out: f64 = (0..3).map(|c| (p.x[c] - centre[c]) * p.normal[c]).sum();
                assert!(out > 0.0, "{file}: normal points into the volume");
                // t = p projected on the plane, normalised
                let pn: f64 = (0..3).map(|c| direction[c] * p.normal[c]).sum();
                let tp: Vec<f64> = (0..3).map(|c| direction[c] - pn * p.normal[c]).collect();
                let tl = tp.iter().map(|v| v * v).sum::<f64>().sqrt();
                for (t, q) in p.tangent.iter().zip(&tp) {
                    assert!((t - q / tl).abs() < 1e-12, "{file} tangent");
                }
            }
        }
        let sum: f64 = fp.points.iter().map(|p| p.area).sum();
        eprintln!(
            "{file} '{group}': {} faces, {} points, area {sum:.15} (faces {area_sum:.15}), ∫N_aN_b dA off the closed form by {worst:.2e} of the face area",
            faces.len(),
            fp.points.len()
        );
        assert!((sum - total).abs() < 1e-12 * total, "{sum} vs {total}");
        assert!((area_sum - total).abs() < 1e-12 * total);
        assert!(worst < 1e-12, "{worst:e}");
    }
}

/// The bar case with the strip `strip` (TOML lines) and `extra` tables.
fn bar_case(dir: &Path, strip: &str, extra: &str) -> Case {
    let text = case_text(&root().join("meshes/damper_bar.msh"), strip, extra);
    Case::from_str(&text, &dir.join("bar.toml")).unwrap()
}

/// Strip parameters shared by the face and the line strip (per area for the face).
const KU: f64 = 1.2e9;
const KV: f64 = 4.0e9;
const MU: f64 = 0.3;
const PRELOAD: f64 = 1000.0;

/// The face strip on `pads`.
fn face_strip(gauss: usize, kn: f64, distribution: &str) -> String {
    format!(
        "face = \"pads\"\ndirection = [1.0, 0.0, 0.0]\ngauss = {gauss}\nkt = {KU:e}\nkn = {kn:e}\nmu = {MU}\npreload = {PRELOAD}\n{distribution}\n"
    )
}

/// The line strip of the same bar by hand: stations at the nodes x_j = jL/40, the tangential
/// weight 1/4 on the x rows of the four nodes of the section at x_j (both pads, both edges), the
/// normal weight −1/4 on the z rows of the two nodes at z = 0 and +1/4 at z = a (the pads'
/// outward normals; given when kn > 0), k per length = k per area × the two pads' width 2a. The
/// clamped section x = 0 has no free rows: its weights are 0.
fn line_strip(m: &Mesh, gauss: usize, kn: f64, distribution: &str) -> String {
    let h = L / NX as f64;
    let mut dofs = Vec::new();
    let mut sections = Vec::new();
    for j in 0..=NX {
        let x = j as f64 * h;
        let mut nodes: Vec<(usize, f64)> = m
            .coords
            .iter()
            .enumerate()
            .filter(|(_, c)| (c[0] - x).abs() < 1e-9)
            .map(|(i, c)| (i, c[2]))
            .collect();
        assert_eq!(nodes.len(), 4, "section x = {x}");
        nodes.sort_by_key(|n| n.0);
        if j > 0 {
            for &(i, _) in &nodes {
                dofs.push(3 * i);
                dofs.push(3 * i + 2);
            }
        }
        sections.push(nodes);
    }
    let table = |normal: bool| -> String {
        let rows: Vec<String> = sections
            .iter()
            .enumerate()
            .map(|(j, nodes)| {
                let w: Vec<String> = dofs
                    .iter()
                    .map(|&d| {
                        let node = nodes.iter().find(|n| n.0 == d / 3).filter(|_| j > 0);
                        let v = match node {
                            Some(_) if !normal && d % 3 == 0 => 0.25,
                            Some(&(_, z)) if normal && d % 3 == 2 => {
                                if z < 0.5 * A {
                                    -0.25
                                } else {
                                    0.25
                                }
                            }
                            _ => 0.0,
                        };
                        format!("{v:e}")
                    })
                    .collect();
                format!("[{}]", w.join(", "))
            })
            .collect();
        format!("[{}]", rows.join(",\n"))
    };
    let stations: Vec<String> = (0..=NX).map(|j| format!("{:e}", j as f64 * h)).collect();
    // like the face strip, the normal motion only with kn > 0 (the normal weights would also
    // apply the preload to the structure as a static load)
    let normal = if kn > 0.0 {
        format!("normal = {}\n", table(true))
    } else {
        String::new()
    };
    format!(
        "dofs = [{}]\nstations = [{}]\ntangential = {}\n{normal}gauss = {gauss}\nkt = {:e}\nkn = {:e}\nmu = {MU}\npreload = {PRELOAD}\n{distribution}\n",
        dofs.iter().map(|d| d.to_string()).collect::<Vec<_>>().join(", "),
        stations.join(", "),
        table(false),
        KU * 2.0 * A,
        kn * 2.0 * A,
    )
}

fn build(case: &Case) -> StructuralModel {
    model::build(case, &mut |_| {}).unwrap()
}

/// Σ k·w per row of a combination (k the point's stiffness).
fn add_weighted(acc: &mut BTreeMap<usize, f64>, k: f64, dofs: &[usize], weights: &[f64]) {
    for (&d, &w) in dofs.iter().zip(weights) {
        *acc.entry(d).or_insert(0.0) += k * w;
    }
}

/// On the bar's pads (flat, 2 × 40 rectangles of 31.25 mm × 10 mm), the face strip's points at
/// each position add up to the hand-built line strip's point there: Σ k_t, Σ k_n, Σ n0 and the
/// stiffness-weighted DOF weights Σ k_t w_t, Σ k_n w_n row by row, to 1e-12 (relative), for the
/// uniform and the quadratic (U-shaped and centre-heavy) distributions and 1 to 3 Gauss points.
#[test]
fn face_strip_adds_up_to_the_line_strip_of_the_same_length_width_and_load() {
    let dir = tempfile::tempdir().unwrap();
    let m = mesh("damper_bar.msh");
    let mut worst: f64 = 0.0;
    for gauss in 1..=3 {
        for distribution in [
            "",
            "distribution = \"quadratic\"\nc = 0.8",
            "distribution = \"quadratic\"\nc = -0.6",
        ] {
            let face = bar_case(dir.path(), &face_strip(gauss, KV, distribution), "");
            let line = bar_case(dir.path(), &line_strip(&m, gauss, KV, distribution), "");
            let model = build(&face);
            let fp = strip_points(&face, 0, &model).unwrap();
            let lp = strip_points(&line, 0, &model).unwrap();
            assert_eq!(lp.len(), NX * gauss);
            // 2 pads × g points across the width per line point; the points next to the clamped
            // section move too, so none is left out
            let per = 2 * gauss;
            assert_eq!(fp.len(), per * lp.len(), "gauss {gauss}");
            let preload: f64 = fp.iter().map(|p| p.1.n0.unwrap()).sum();
            assert!((preload - PRELOAD).abs() < 1e-12 * PRELOAD);
            for (pt, (s, e)) in lp.iter().enumerate() {
                let group: Vec<&(f64, FrictionElement)> =
                    fp[per * pt..per * (pt + 1)].iter().collect();
                for g in &group {
                    assert!((g.0 - s).abs() < 1e-12, "position {} vs {s}", g.0);
                }
                let sum = |f: &dyn Fn(&FrictionElement) -> f64| {
                    group.iter().map(|g| f(&g.1)).sum::<f64>()
                };
                let rel = |a: f64, b: f64| (a - b).abs() / b.abs().max(1e-300);
                worst = worst
                    .max(rel(sum(&|e| e.kt.unwrap()), e.kt.unwrap()))
                    .max(rel(sum(&|e| e.kn), e.kn))
                    .max(rel(sum(&|e| e.n0.unwrap()), e.n0.unwrap()));
                for normal in [false, true] {
                    let mut a = BTreeMap::new();
                    let mut b = BTreeMap::new();
                    for g in &group {
                        let (k, w) = if normal {
                            (g.1.kn, g.1.normal.as_ref().unwrap())
                        } else {
                            (g.1.kt.unwrap(), &g.1.tangential)
                        };
                        add_weighted(&mut a, k, &w.dofs, &w.weights);
                    }
                    let (k, w) = if normal {
                        (e.kn, e.normal.as_ref().unwrap())
                    } else {
                        (e.kt.unwrap(), &e.tangential)
                    };
                    add_weighted(&mut b, k, &w.dofs, &w.weights);
                    // the faces' normals carry the mesh file's rounding of the coordinates
                    // (printed to 16 digits), so a point's direction can lean by ~1e-16 and put
                    // weights of that size on the other components' rows
                    let scale = b.values().fold(0.0f64, |x, v| x.max(v.abs()));
                    for (d, v) in &a {
                        let reference = b.get(d).copied().unwrap_or(0.0);
                        worst = worst.max((v - reference).abs() / scale);
                    }
                    for d in b.keys() {
                        assert!(a.contains_key(d), "row {d} of line point {pt} missing");
                    }
                }
            }
        }
    }
    eprintln!("face strip against the line strip: worst relative difference {worst:.2e}");
    assert!(worst < 1e-12, "{worst:e}");
}

/// The map frequencies of the response comparison: below and at the resonance peak (1341 Hz),
/// where slip has run in from the tip.
const MAP_HZ: [f64; 2] = [1330.0, 1341.0];

/// The bar's forced response near its first axial resonance at H = 1 with the exact cycle, with
/// the face strip and with the hand-built line strip (no normal motion, as the paper's bar; the
/// normal weights are compared above): at the chosen frequencies the tip's harmonics agree to 1e-6 of their amplitude, and each face
/// point's map equals its line point's (no sample in another state away from a transition,
/// transition angles within 1e-6 rad; measured 2.5e-12 of the amplitude, 0 samples, 8e-12 rad);
/// the map at the peak has slip run in from the tip next to stick.
#[test]
fn mesh_case_with_a_face_strip_responds_as_the_line_strip() {
    let dir = tempfile::tempdir().unwrap();
    let m = mesh("damper_bar.msh");
    let extra = format!(
        "evaluation = \"analytic\"\nmap = 180\nmap_hz = [{}, {}]\n\n[harmonic_balance]\nharmonics = 1\n\n[continuation]\nstart_hz = 1300.0\nend_hz = 1360.0\nstep_hz = 2.0\nmax_step_hz = 5.0\n",
        MAP_HZ[0], MAP_HZ[1]
    );
    let face = solve(&bar_case(dir.path(), &face_strip(2, 0.0, ""), &extra));
    let line = solve(&bar_case(dir.path(), &line_strip(&m, 2, 0.0, ""), &extra));
    assert_eq!(face.maps.len(), MAP_HZ.len());
    // four face points (two pads, two Gauss points across) per line point
    let agree = agreement(&face, &line, 4, 1e-6);
    assert!(agree.harmonics <= 1e-6, "{:e}", agree.harmonics);
    assert_eq!(agree.differ, 0);
    assert!(agree.angle < 1e-6, "{:e}", agree.angle);
    assert!(agree.mixed, "no map with both stick and slip");
}

/// The error text of a case that fails to load or to build its strip points.
fn failure(dir: &Path, strip: &str) -> String {
    let text = format!(
        "[model]\nmesh = \"{}\"\nmaterial = {{ young = 200e9, poisson = 0.3, density = 7800.0 }}\nclamp = [\"clamp\"]\n\n[excitation]\ngroup = \"tip\"\nforce = [1.0, 0.0, 0.0]\n\n[[strip]]\n{strip}\nkt = 1e9\nmu = 0.3\npreload = 10.0\n",
        root().join("meshes/damper_bar.msh").display()
    );
    let case = match Case::from_str(&text, &dir.join("bad.toml")) {
        Ok(c) => c,
        Err(e) => return e.to_string(),
    };
    let model = match model::build(&case, &mut |_| {}) {
        Ok(m) => m,
        Err(e) => return e.to_string(),
    };
    match strip_points(&case, 0, &model) {
        Ok(_) => panic!("no error for {strip}"),
        Err(e) => e.to_string(),
    }
}

/// Face strips given wrongly are input errors naming the key (and the face element or group).
#[test]
fn face_strip_errors_name_the_key() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let checks: [(&str, &[&str]); 6] = [
        (
            "face = \"pads\"\ndirection = [0.0, 0.2, 1.0]",
            &["strip[0].face", "face element", "'pads'", "normal"],
        ),
        ("face = \"pads\"", &["strip[0].face", "direction"]),
        (
            "face = \"volume\"\ndirection = [1.0, 0.0, 0.0]",
            &["strip[0].face", "surface group", "dim 3"],
        ),
        (
            "face = \"pad\"\ndirection = [1.0, 0.0, 0.0]",
            &["strip[0].face", "'pad'", "did you mean 'pads'"],
        ),
        (
            "face = \"pads\"\ndirection = [1.0, 0.0, 0.0]\nstations = [0.0, 1.0]",
            &["strip[0].stations", "matrix rows"],
        ),
        (
            "face = \"pads\"\ndirection = [0.0, 0.0, 0.0]",
            &["strip[0].direction", "zero"],
        ),
    ];
    for (strip, wanted) in checks {
        let msg = failure(d, strip);
        for w in wanted {
            assert!(msg.contains(w), "{strip:?}: {w:?} not in: {msg}");
        }
    }
    let msg = failure(
        d,
        "face = \"pads\"\ndirection = [1.0, 0.0, 0.0]\ndistribution = \"stations\"\nvalues = [1.0, 2.0]",
    );
    assert!(msg.contains("strip[0].distribution"), "{msg}");
}
