//! SAMA and node-to-node contact pairs on the bundled shrouded sector (N = 24): conforming and
//! non-conforming shroud faces, and the `nlrom contact` command.

mod support;

use support::cli::nlrom;

use std::path::Path;

use faer::c64;
use nlrom::case::{Case, ContactModel};
use nlrom::cyclic::{match_frontiers, CyclicGeometry};
use nlrom::interface::{build_interfaces, ContactInterface, ContactPair};
use nlrom::mesh::faces::group_faces;
use nlrom::mesh::msh::read_msh;
use nlrom::mesh::Mesh;

fn case(name: &str) -> Case {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("cases/{name}.toml"));
    Case::load(&path).unwrap()
}

fn setup(name: &str) -> (Case, Mesh, CyclicGeometry) {
    let case = case(name);
    let mesh = read_msh(case.model.mesh.as_ref().unwrap()).unwrap();
    let geom = CyclicGeometry::from_case(case.cyclic.as_ref().unwrap()).unwrap();
    (case, mesh, geom)
}

fn interface(case: &Case, mesh: &Mesh, geom: &CyclicGeometry) -> ContactInterface {
    let mut v = build_interfaces(case, mesh, Some(geom)).unwrap();
    assert_eq!(v.len(), 1);
    v.pop().unwrap()
}

fn dist(a: [f64; 3], b: [f64; 3]) -> f64 {
    ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
}

fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// Frame rows orthonormal and right-handed (t1 × t2 = n).
fn check_frame(f: &[[f64; 3]; 3]) {
    for i in 0..3 {
        for j in 0..3 {
            let e = if i == j { 1.0 } else { 0.0 };
            assert!((dot(f[i], f[j]) - e).abs() < 1e-14, "{f:?}");
        }
    }
    let c = [
        f[0][1] * f[1][2] - f[0][2] * f[1][1],
        f[0][2] * f[1][0] - f[0][0] * f[1][2],
        f[0][0] * f[1][1] - f[0][1] * f[1][0],
    ];
    assert!(dist(c, f[2]) < 1e-14, "{f:?}");
}

/// Checks of eqs 30–32 that hold for any interface, to 1e-12.
fn check_sums(iface: &ContactInterface, kt: f64, kn: f64, n0: f64) {
    for p in &iface.pairs {
        let w: f64 = p.weights.iter().sum();
        assert!((w - 1.0).abs() < 1e-12, "eq 30 at node {}", p.contact_node);
        assert!(p.weights.iter().all(|&w| (0.0..=1.0).contains(&w)));
        let st: f64 = p.kt.iter().sum();
        let sn: f64 = p.kn.iter().sum();
        let s0: f64 = p.n0.iter().sum();
        assert!(
            (st - kt).abs() <= 1e-12 * kt,
            "Σ k_tj at {}",
            p.contact_node
        );
        assert!(
            (sn - kn).abs() <= 1e-12 * kn,
            "Σ k_nj at {}",
            p.contact_node
        );
        assert!((s0 - p.n0_node).abs() <= 1e-12 * p.n0_node.abs());
        check_frame(&p.frame);
    }
    let n = iface.pairs.len() as f64;
    assert!((iface.sum_kt - n * kt).abs() <= 1e-12 * n * kt);
    assert!((iface.sum_kn - n * kn).abs() <= 1e-12 * n * kn);
    assert!((iface.sum_n0 - n0).abs() <= 1e-12 * n0, "{}", iface.sum_n0);
}

#[test]
fn conforming_shroud_gives_one_target_per_node() {
    let (case, mesh, geom) = setup("shroud_conforming");
    let c = &case.contact[0];
    let iface = interface(&case, &mesh, &geom);
    // The target face (θ = 0) is brought onto the contact face (θ = α) by R_α: σ = +1.
    assert_eq!(iface.sigma, 1);
    assert_eq!(iface.model, ContactModel::NodeToNode);
    assert_eq!(iface.contact_nodes, 65);
    assert_eq!(iface.pairs.len(), 65);
    assert!(iface.unprojected.is_empty());
    check_sums(&iface, c.kt, c.kn, c.n0);

    // Independent pairing: the cyclic frontier matcher on the two shroud faces.
    let fp = match_frontiers(&mesh, &geom, "shroud_target", "shroud_contact").unwrap();
    for p in &iface.pairs {
        assert_eq!(p.weights, vec![1.0]);
        let k = fp.high.iter().position(|&h| h == p.contact_index).unwrap();
        assert_eq!(p.target_indices, vec![fp.low[k]], "node {}", p.contact_node);
        let xt = geom.rotate_point(mesh.coords[fp.low[k] as usize], 1);
        assert!(dist(xt, mesh.coords[p.contact_index as usize]) < 1e-12);
        assert!(p.distance < 1e-12 && p.gap.abs() < 1e-12);
    }

    // SAMA on the same mesh reproduces the node-to-node pairs exactly.
    let mut sama_case = case.clone();
    sama_case.contact[0].model = ContactModel::Sama;
    let sama = interface(&sama_case, &mesh, &geom);
    assert_eq!(sama.sigma, 1);
    assert_eq!(sama.pairs.len(), 65);
    for (a, b) in sama.pairs.iter().zip(&iface.pairs) {
        assert_eq!(a.contact_node, b.contact_node);
        assert_eq!(a.targets, b.targets);
        assert_eq!(a.weights, vec![1.0]);
        assert_eq!(a.n0, b.n0);
    }
}

#[test]
fn conforming_shroud_normal_points_to_the_contact_body() {
    let (case, mesh, geom) = setup("shroud_conforming");
    let iface = interface(&case, &mesh, &geom);
    // The contact face lies on the plane θ = α; the contact body (this sector's shroud) is at
    // θ < α, so n = −e_θ(α) = (sin α, −cos α, 0).
    let a = geom.alpha;
    for p in &iface.pairs {
        assert!(
            dist(p.frame[2], [a.sin(), -a.cos(), 0.0]) < 1e-12,
            "{:?}",
            p.frame
        );
    }
}

#[test]
fn tributary_areas_sum_to_the_shroud_face_and_share_the_preload() {
    let (case, mesh, geom) = setup("shroud_conforming");
    let iface = interface(&case, &mesh, &geom);
    // Shroud face: r ∈ [0.25, 0.26] × z ∈ [0, 0.03].
    let total: f64 = iface.pairs.iter().map(|p| p.area).sum();
    assert!((total - 0.01 * 0.03).abs() < 1e-12 * 3e-4, "{total}");
    // Same total from the faces' own area rule (independent quadrature of |∂x/∂u × ∂x/∂v|).
    let faces = group_faces(&mesh, "shroud_contact").unwrap();
    let by_faces: f64 = faces
        .iter()
        .map(|f| {
            let xs: Vec<[f64; 3]> = f.nodes.iter().map(|&n| mesh.coords[n as usize]).collect();
            nlrom::mesh::faces::face_area(f.kind, &xs)
        })
        .sum();
    assert!((total - by_faces).abs() < 1e-15);
    for p in &iface.pairs {
        let share = case.contact[0].n0 * p.area / total;
        assert!((p.n0_node - share).abs() < 1e-12 * share);
    }
}

#[test]
fn nonconforming_shroud_weights_satisfy_eqs_29_to_32() {
    let (case, mesh, geom) = setup("shroud_nonconforming");
    let c = &case.contact[0];
    let iface = interface(&case, &mesh, &geom);
    assert_eq!(iface.sigma, 1);
    assert_eq!(iface.pairs.len(), 65);
    assert!(iface.unprojected.is_empty());
    check_sums(&iface, c.kt, c.kn, c.n0);
    let faces = group_faces(&mesh, "shroud_target").unwrap();
    let mut multi = 0;
    for p in &iface.pairs {
        let xc = mesh.coords[p.contact_index as usize];
        // Same plane: the contact node is its own virtual node.
        assert!(p.distance < 1e-12 && p.gap.abs() < 1e-12, "{}", p.distance);
        assert!(dist(p.virtual_point, xc) < 1e-12);
        // t_v inside its face: barycentric coordinates in the (flat) face's corner triangle,
        // computed from the placed corner positions, all ≥ 0.
        let face = faces.iter().find(|f| f.surface_tag == p.face).unwrap();
        let corners: Vec<[f64; 3]> = face.nodes[..3]
            .iter()
            .map(|&n| geom.rotate_point(mesh.coords[n as usize], 1))
            .collect();
        let b = barycentric(&corners, p.virtual_point);
        assert!(
            b.iter().all(|&x| x >= -1e-12),
            "{b:?} at node {}",
            p.contact_node
        );
        // Every target node belongs to that face.
        assert!(p.target_indices.iter().all(|t| face.nodes.contains(t)));
        // Eq 29 recomputed: w_j·d_j is the same for all j (d_j in the contact plane).
        if p.targets.len() > 1 {
            multi += 1;
            assert_eq!(p.targets.len(), 6, "triangle6 faces: n_T = 6");
            let wd: Vec<f64> = p
                .target_indices
                .iter()
                .zip(&p.weights)
                .map(|(&t, w)| {
                    let xt = geom.rotate_point(mesh.coords[t as usize], 1);
                    let d = [
                        p.virtual_point[0] - xt[0],
                        p.virtual_point[1] - xt[1],
                        p.virtual_point[2] - xt[2],
                    ];
                    let dn = dot(d, p.frame[2]);
                    w * (dot(d, d) - dn * dn).sqrt()
                })
                .collect();
            for x in &wd {
                assert!((x - wd[0]).abs() < 1e-12 * wd[0], "{wd:?}");
            }
        } else {
            let xt = geom.rotate_point(mesh.coords[p.target_indices[0] as usize], 1);
            // Coincident within the tolerance (one unstructured target node lies 8e-8 m from a
            // contact node; eq 29 then gives it weight 1).
            let d = dist(xt, xc);
            assert!(
                d <= iface.coincident_tolerance,
                "node {}: {d:e}",
                p.contact_node
            );
        }
    }
    assert!(multi > 20, "{multi} non-coincident contact nodes");
}

/// Barycentric coordinates of `p` in the triangle `t` (p in its plane).
fn barycentric(t: &[[f64; 3]], p: [f64; 3]) -> [f64; 3] {
    let sub = |a: [f64; 3], b: [f64; 3]| [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
    let (v0, v1, v2) = (sub(t[1], t[0]), sub(t[2], t[0]), sub(p, t[0]));
    let (d00, d01, d11) = (dot(v0, v0), dot(v0, v1), dot(v1, v1));
    let (d20, d21) = (dot(v2, v0), dot(v2, v1));
    let den = d00 * d11 - d01 * d01;
    let v = (d11 * d20 - d01 * d21) / den;
    let w = (d00 * d21 - d01 * d20) / den;
    [1.0 - v - w, v, w]
}

#[test]
fn nonconforming_node_to_node_is_an_error_listing_nodes() {
    let (mut case, mesh, geom) = setup("shroud_nonconforming");
    case.contact[0].model = ContactModel::NodeToNode;
    let e = build_interfaces(&case, &mesh, Some(&geom)).unwrap_err();
    assert_eq!(e.exit_code(), 2);
    let msg = e.to_string();
    assert!(
        msg.contains("'shroud'") && msg.contains("do not conform"),
        "{msg}"
    );
    assert!(msg.contains("model = \"sama\""), "{msg}");
    assert!(msg.contains(" at ("), "lists nodes with coordinates: {msg}");
}

#[test]
fn rigid_motions_give_zero_relative_displacement() {
    let (case, mesh, geom) = setup("shroud_nonconforming");
    let iface = interface(&case, &mesh, &geom);
    let d = [1.3e-5, -0.7e-5, 2.1e-5];
    let cd = d.map(|x| c64::new(x, 0.0));
    // Both surfaces translated by d in the contact sector's axes: the target nodes' own
    // displacement is R^{-σ} d (harmonic index 0, φ = 0).
    let ut = geom
        .rotate_vector(d, -iface.sigma)
        .map(|x| c64::new(x, 0.0));
    // Rigid rotation of the whole annulus about the axis (k = 0): u = ω × x.
    let w = [0.0, 0.0, 1e-4];
    let spin = |x: [f64; 3]| {
        [
            w[1] * x[2] - w[2] * x[1],
            w[2] * x[0] - w[0] * x[2],
            w[0] * x[1] - w[1] * x[0],
        ]
        .map(|v| c64::new(v, 0.0))
    };
    for p in &iface.pairs {
        for &t in &p.target_indices {
            let r = iface.relative_displacement(p, 0.0, cd, ut);
            assert!(r.iter().all(|x| x.norm() < 1e-20), "{r:?}");
            // Rotation: only exact for coincident pairs; for the others u_c − R u_t = ω × (x_c − R x_t).
            let xc = mesh.coords[p.contact_index as usize];
            let xt = mesh.coords[t as usize];
            let r = iface.relative_displacement(p, 0.0, spin(xc), spin(xt));
            let xt_placed = geom.rotate_point(xt, iface.sigma);
            let expect = spin([
                xc[0] - xt_placed[0],
                xc[1] - xt_placed[1],
                xc[2] - xt_placed[2],
            ]);
            for k in 0..3 {
                let e: c64 = (0..3).map(|m| expect[m] * p.frame[k][m]).sum();
                assert!((r[k] - e).norm() < 1e-18, "{r:?} vs {e:?}");
            }
        }
    }
}

#[test]
fn pair_forces_are_the_adjoint_of_the_relative_displacement() {
    let (case, mesh, geom) = setup("shroud_nonconforming");
    let iface = interface(&case, &mesh, &geom);
    let phi = 2.0 * std::f64::consts::PI * 5.0 / 24.0;
    let p = &iface.pairs[7];
    let u_c = [c64::new(0.3, -1.1), c64::new(0.7, 0.2), c64::new(-0.4, 0.9)];
    let u_t = [c64::new(-0.2, 0.5), c64::new(1.3, -0.6), c64::new(0.1, 0.8)];
    let f = [c64::new(0.9, 0.4), c64::new(-0.5, 1.2), c64::new(0.6, -0.3)];
    let r = iface.relative_displacement(p, phi, u_c, u_t);
    let (f_c, f_t) = iface.pair_forces(p, phi, f);
    // rᴴ f = u_cᴴ f_c + u_tᴴ f_t
    let lhs: c64 = (0..3).map(|k| r[k].conj() * f[k]).sum();
    let rhs: c64 = (0..3)
        .map(|k| u_c[k].conj() * f_c[k] + u_t[k].conj() * f_t[k])
        .sum();
    assert!((lhs - rhs).norm() < 1e-14, "{lhs} vs {rhs}");
    // The target's displacement enters with e^{iσφ} R^σ: a target motion u_t = e^{-iσφ} R^{-σ} u
    // cancels a contact motion u.
    let e = c64::new(0.0, -(iface.sigma as f64) * phi).exp();
    let back = geom.rotate_vector([1.0, 0.0, 0.0], -iface.sigma);
    let ut = back.map(|x| e * x);
    let uc = [c64::new(1.0, 0.0), c64::new(0.0, 0.0), c64::new(0.0, 0.0)];
    let r = iface.relative_displacement(p, phi, uc, ut);
    assert!(r.iter().all(|x| x.norm() < 1e-15), "{r:?}");
}

#[test]
fn contact_command_json_has_the_contract_keys() {
    let out = nlrom(&["contact", "cases/shroud_nonconforming.toml", "--json"]);
    assert_eq!(
        out.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).expect("one JSON object");
    let i = &v["interfaces"][0];
    assert_eq!(i["name"], "shroud");
    assert_eq!(i["model"], "sama");
    assert_eq!(i["sigma"], 1);
    assert_eq!(i["contact_nodes"], 65);
    assert_eq!(i["pairs"].as_array().unwrap().len(), 65);
    assert_eq!(i["unprojected"].as_array().unwrap().len(), 0);
    let p = &i["pairs"][0];
    for key in ["contact_node", "targets", "weights", "distance", "normal"] {
        assert!(!p[key].is_null(), "pair key {key}");
    }
    let n0 = i["sum_n0"].as_f64().unwrap();
    assert!((n0 - 113.0).abs() < 1e-12 * 113.0);
    assert!((i["sum_kt"].as_f64().unwrap() - 65.0e8).abs() < 1e-12 * 65e8);
    assert!(v["wall_seconds"].as_f64().is_some());

    let text = nlrom(&["contact", "cases/shroud_conforming.toml"]);
    assert_eq!(text.status.code(), Some(0));
    let s = String::from_utf8_lossy(&text.stdout);
    assert!(
        s.contains("model node-to-node, σ = 1, 65 contact nodes, 65 projected"),
        "{s}"
    );
}

#[test]
fn contact_command_bad_input_exits_2() {
    let dir = tempfile::tempdir().unwrap();
    let root = env!("CARGO_MANIFEST_DIR");
    let text = std::fs::read_to_string(format!("{root}/cases/shroud_conforming.toml"))
        .unwrap()
        .replace("../meshes/", &format!("{root}/meshes/"))
        .replace("target = \"shroud_target\"", "target = \"hub\"");
    let path = dir.path().join("bad.toml");
    std::fs::write(&path, text).unwrap();
    let out = nlrom(&["contact", path.to_str().unwrap(), "--json"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(out.stdout.is_empty());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("do not face each other") && err.contains("'hub'"),
        "{err}"
    );

    let out = nlrom(&["contact", "cases/sector_modes.toml"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("no [[contact]]"));
}

#[test]
fn swapped_groups_give_sigma_minus_one_and_the_inverse_pairs() {
    let (mut case, mesh, geom) = setup("shroud_conforming");
    let forward = interface(&case, &mesh, &geom);
    let c = &mut case.contact[0];
    std::mem::swap(&mut c.contact, &mut c.target);
    let back = interface(&case, &mesh, &geom);
    // The contact face (θ = α) is now the target: R_α^{-1} brings it onto θ = 0.
    assert_eq!(back.sigma, -1);
    assert_eq!(back.pairs.len(), 65);
    for p in &back.pairs {
        let q = forward
            .pairs
            .iter()
            .find(|q| q.contact_index == p.target_indices[0])
            .unwrap();
        assert_eq!(q.target_indices, vec![p.contact_index]);
        // Outward normal of the (rotated) θ = α face, towards the shroud at θ > 0: +e_θ(0) = +y.
        assert!(
            dist(p.frame[2], [0.0, 1.0, 0.0]) < 1e-12,
            "{:?}",
            p.frame[2]
        );
    }
}

#[test]
fn sector8_model_places_the_target_with_its_own_sector_angle() {
    let (mut case, _, _) = setup("shroud_conforming");
    let root = env!("CARGO_MANIFEST_DIR");
    case.model.mesh = Some(Path::new(root).join("meshes/sector8.msh"));
    case.cyclic.as_mut().unwrap().sectors = 8;
    let mesh = read_msh(case.model.mesh.as_ref().unwrap()).unwrap();
    let geom = CyclicGeometry::from_case(case.cyclic.as_ref().unwrap()).unwrap();
    let iface = interface(&case, &mesh, &geom);
    assert_eq!(iface.sigma, 1);
    assert_eq!(iface.pairs.len(), 45);
    let fp = match_frontiers(&mesh, &geom, "shroud_target", "shroud_contact").unwrap();
    for p in &iface.pairs {
        let k = fp.high.iter().position(|&h| h == p.contact_index).unwrap();
        assert_eq!(p.target_indices, vec![fp.low[k]]);
    }
    // With the wrong sector count (24 instead of 8) the faces do not meet under any rotation.
    case.cyclic.as_mut().unwrap().sectors = 24;
    let wrong = CyclicGeometry::from_case(case.cyclic.as_ref().unwrap()).unwrap();
    let e = build_interfaces(&case, &mesh, Some(&wrong)).unwrap_err();
    assert!(e.to_string().contains("do not face each other"), "{e}");
}

#[test]
fn pairs_become_friction_elements_of_the_harmonic_balance() {
    use nlrom::contact::law::Variant;
    use nlrom::contact::pairs::{PairSet, SectorCoupling};
    let (case, mesh, geom) = setup("shroud_nonconforming");
    let iface = interface(&case, &mesh, &geom);
    // DOF vector: every contact and target node, in tag order.
    let mut tags: Vec<u64> = iface
        .pairs
        .iter()
        .flat_map(|p| std::iter::once(p.contact_node).chain(p.targets.iter().copied()))
        .collect();
    tags.sort_unstable();
    tags.dedup();
    let rows = |t: u64| {
        tags.binary_search(&t)
            .ok()
            .map(|i| [3 * i, 3 * i + 1, 3 * i + 2])
    };
    let elements = iface.elements(rows).unwrap();
    let n_pairs: usize = iface.pairs.iter().map(|p| p.targets.len()).sum();
    assert_eq!(elements.len(), n_pairs);
    let kt: f64 = elements.iter().map(|e| e.params.kt).sum();
    let n0: f64 = elements.iter().map(|e| e.params.n0).sum();
    let rate: f64 = elements.iter().map(|e| e.preload_rate).sum();
    assert!((kt - iface.sum_kt).abs() < 1e-12 * kt);
    assert!((n0 - 113.0).abs() < 1e-12 * 113.0);
    // ∂(Σ n0_j)/∂n0 = 1, and each rate is n0_j / n0.
    assert!((rate - 1.0).abs() < 1e-12);
    for e in &elements {
        assert!((e.preload_rate * 113.0 - e.params.n0).abs() < 1e-12);
        assert_eq!(e.sigma, 1);
        assert!(e.params.mu == 0.5);
    }
    // The contact module accepts them (orthonormal right-handed frames, rows in range).
    let coupling = SectorCoupling {
        sectors: 24,
        rotation: geom.rotation(1),
        harmonic_indices: vec![0, 3, 6, 9],
    };
    PairSet::new(3 * tags.len(), Variant::OneD, elements, Some(coupling)).unwrap();
    // A node missing from the DOF vector is an error naming it.
    let first = iface.pairs[0].targets[0];
    let e = iface
        .elements(|t| if t == first { None } else { rows(t) })
        .unwrap_err();
    assert!(
        e.to_string().contains(&format!("target node {first}")),
        "{e}"
    );
}

#[test]
fn axial_misalignment_of_the_bundled_shroud_unprojects_the_uncovered_row() {
    // Conforming shroud, target shifted 1 mm along the axis (a fifth of the 5 mm contact cells):
    // it covers z ∈ [0.001, 0.031], so the 5 contact nodes on z = 0 fall outside it and every
    // other node gets SAMA weights on the shifted target faces.
    let (mut case, mesh, geom) = setup("shroud_conforming");
    case.contact[0].model = ContactModel::Sama;
    case.contact[0].misalignment = Some(nlrom::case::Misalignment {
        translate: [0.0, 0.0, 0.001],
        rotate: None,
    });
    let iface = interface(&case, &mesh, &geom);
    assert_eq!(iface.sigma, 1);
    let mut bottom: Vec<u64> = mesh
        .nodes_of("shroud_contact")
        .unwrap()
        .into_iter()
        .filter(|&n| mesh.coords[n as usize][2].abs() < 1e-12)
        .map(|n| mesh.node_tags[n as usize])
        .collect();
    bottom.sort_unstable();
    let unprojected: Vec<u64> = iface.unprojected.iter().map(|u| u.node).collect();
    assert_eq!(unprojected, bottom);
    assert_eq!(bottom.len(), 5);
    assert_eq!(iface.pairs.len(), 60);
    check_sums(&iface, 1e8, 1e8, 113.0);
    for p in &iface.pairs {
        let z = mesh.coords[p.contact_index as usize][2];
        // Rows at z = 0.0025·k: the shifted target nodes sit at 0.001 + 0.0025·k, so no node
        // coincides and every contact node is spread over a triangle6's 6 nodes.
        assert_eq!(p.targets.len(), 6, "node {} at z = {z}", p.contact_node);
        assert!(p.distance < 1e-12);
    }
}

/// Largest |u_c − Σ_j w_j R^σ u_tj| (m) over the contact nodes for the rigid rotation u = ω × x
/// of the whole annulus (harmonic index 0), with the pairs' weights used as interpolation
/// coefficients (the relative displacement the interpolated coupling's element sees), and the
/// largest stretch |u_c − R^σ u_tj| of a single array pair c–t_j.
fn rigid_rotation_residuals(
    iface: &ContactInterface,
    mesh: &Mesh,
    geom: &CyclicGeometry,
) -> (f64, f64) {
    let w = [0.0, 0.0, 1e-4];
    let spin = |x: [f64; 3]| {
        [
            w[1] * x[2] - w[2] * x[1],
            w[2] * x[0] - w[0] * x[2],
            w[0] * x[1] - w[1] * x[0],
        ]
    };
    let (mut interp, mut pair): (f64, f64) = (0.0, 0.0);
    for p in &iface.pairs {
        let uc = spin(mesh.coords[p.contact_index as usize]);
        let mut sum = [0.0; 3];
        for (&t, &wj) in p.target_indices.iter().zip(&p.weights) {
            let ut = geom.rotate_vector(spin(mesh.coords[t as usize]), iface.sigma);
            pair = pair.max(dist(uc, ut));
            for c in 0..3 {
                sum[c] += wj * ut[c];
            }
        }
        interp = interp.max(dist(uc, sum));
    }
    (interp, pair)
}

/// The cause of the paper comparison's stiff SAMA results (`docs/validation.md`): on the
/// non-conforming shroud the array's pairs c–t_j join points up to a target element apart, so a
/// rigid rotation (ω = 1e-4 rad about the axis, |u| ≈ 2.6e-5 m) stretches them by up to
/// |ω| × |x_c − x_tj| (measured 2.60e-7 m: 1 % of the motion), and even the inverse-distance
/// combination Σ w_j u_tj misses u(t_v) by 5.2e-8 m (its centre Σ w_j x_tj is up to 0.70 mm off t_v). The
/// interpolated coupling's shape functions reproduce t_v (Σ N_j x_tj = t_v to 1e-12 m) and give
/// no relative displacement under the rotation (below 1e-4 × the 1.8e-7 m coincidence tolerance).
#[test]
fn interpolated_coupling_reproduces_the_virtual_node_and_rigid_rotations() {
    use nlrom::case::SamaCoupling;
    let (mut case, mesh, geom) = setup("shroud_nonconforming");
    let array = interface(&case, &mesh, &geom);
    case.contact[0].coupling = Some(SamaCoupling::Interpolated);
    let interp = interface(&case, &mesh, &geom);
    assert_eq!(interp.pairs.len(), 65);
    assert_eq!(interp.element_count(), 65);
    assert!(array.element_count() > 300, "{}", array.element_count());
    // eq 32 still holds (Σ_j N_j = 1): the shares of k_t, k_n and n0_c over the targets
    assert!((interp.sum_kt - 65.0 * 1e8).abs() < 1e-6 * interp.sum_kt);
    assert!((interp.sum_n0 - 113.0).abs() < 1e-12 * 113.0);
    let mut negative = 0;
    for p in &interp.pairs {
        assert!((p.weights.iter().sum::<f64>() - 1.0).abs() < 1e-12);
        let mut centre = [0.0; 3];
        for (&t, &w) in p.target_indices.iter().zip(&p.weights) {
            let x = geom.rotate_point(mesh.coords[t as usize], interp.sigma);
            for c in 0..3 {
                centre[c] += w * x[c];
            }
            negative += usize::from(w < 0.0);
        }
        // a target node within the coincidence tolerance of t_v takes weight 1 (eq 29's rule)
        let tol = if p.targets.len() == 1 {
            interp.coincident_tolerance
        } else {
            1e-12
        };
        assert!(
            dist(centre, p.virtual_point) <= tol,
            "node {}: {centre:?} vs {:?}",
            p.contact_node,
            p.virtual_point
        );
    }
    // quadratic faces: the corner shape functions are negative inside the face
    assert!(negative > 0);
    let (r_interp, _) = rigid_rotation_residuals(&interp, &mesh, &geom);
    let (r_idw, r_pair) = rigid_rotation_residuals(&array, &mesh, &geom);
    println!("rigid rotation: interpolated {r_interp:.2e} m, inverse-distance combination {r_idw:.2e} m, largest array pair stretch {r_pair:.2e} m");
    // ω × (x_c − t_v): at most 1e-4 × the coincidence tolerance (1.8e-7 m)
    assert!(
        r_interp < 1e-4 * interp.coincident_tolerance,
        "{r_interp:.3e}"
    );
    assert!((r_pair - 2.60e-7).abs() < 0.05e-7, "{r_pair:.3e}");
    assert!(r_idw > 1e-8, "{r_idw:.3e}");
}

/// The complex per-harmonic relative-displacement operator of a pair and its adjoint: the
/// reference the production kinematics (`contact::kinematics`) is checked against.
///
/// For temporal harmonic n on harmonic index k_n, the target node's displacement as seen from the
/// contact sector is e^{iσφ} R_α^σ u_t (`docs/conventions.md` §3; paper eq 33 with σ = ±1), φ = φ_{k_n}
/// = 2πk_n/N the inter-sector phase (rad). The local relative displacement of the pair is
///
///   r_loc = F (u_c − e^{iσφ} R_α^σ u_t) = A_c u_c + A_t u_t,  A_c = F,  A_t = −e^{iσφ} F R_α^σ,
///
/// F = the pair's frame (rows t1, t2, n), so r_loc = (u1, u2, r·n); the normal approach of
/// `docs/conventions.md` §3 is v = −r·n. A local force f_loc acting on the contact node (f_n along +n
/// pushes c away from the target) acts on the nodes as f_c = A_cᴴ f_loc and f_t = A_tᴴ f_loc (the
/// adjoint, so that δr_locᴴ f_loc = δu_cᴴ f_c + δu_tᴴ f_t: virtual work is preserved). For σ = 0 or
/// φ = 0 everything is real. The weights enter the pair's parameters (eq 31), not this operator.
trait PairOperator {
    fn phase_factor(&self, phi: f64) -> c64;
    fn contact_block(&self, pair: &ContactPair) -> [[f64; 3]; 3];
    fn target_block(&self, pair: &ContactPair) -> [[f64; 3]; 3];
    fn relative_displacement(
        &self,
        pair: &ContactPair,
        phi: f64,
        u_c: [c64; 3],
        u_t: [c64; 3],
    ) -> [c64; 3];
    fn pair_forces(&self, pair: &ContactPair, phi: f64, f_loc: [c64; 3]) -> ([c64; 3], [c64; 3]);
}

impl PairOperator for ContactInterface {
    /// e^{iσφ} for the inter-sector phase φ (rad).
    fn phase_factor(&self, phi: f64) -> c64 {
        let a = self.sigma as f64 * phi;
        c64::new(a.cos(), a.sin())
    }

    /// A_c = F: the real 3×3 block (row-major) from u_c to r_loc.
    fn contact_block(&self, pair: &ContactPair) -> [[f64; 3]; 3] {
        pair.frame
    }

    /// −F R_α^σ: the real part of the block from u_t to r_loc, before the phase factor e^{iσφ}.
    fn target_block(&self, pair: &ContactPair) -> [[f64; 3]; 3] {
        let (f, r) = (&pair.frame, &self.rotation);
        std::array::from_fn(|i| {
            std::array::from_fn(|j| -(0..3).map(|k| f[i][k] * r[k][j]).sum::<f64>())
        })
    }

    /// r_loc = F (u_c − e^{iσφ} R_α^σ u_t) for one harmonic: complex amplitudes of the contact
    /// node's and a target node's displacements (m, global axes of their own sectors) → local
    /// relative displacement (t1, t2, n components, m).
    fn relative_displacement(
        &self,
        pair: &ContactPair,
        phi: f64,
        u_c: [c64; 3],
        u_t: [c64; 3],
    ) -> [c64; 3] {
        let a_c = self.contact_block(pair);
        let a_t = self.target_block(pair);
        let e = self.phase_factor(phi);
        let mut r = [c64::new(0.0, 0.0); 3];
        for (i, ri) in r.iter_mut().enumerate() {
            for k in 0..3 {
                *ri += u_c[k] * a_c[i][k] + e * u_t[k] * a_t[i][k];
            }
        }
        r
    }

    /// The nodal forces (N, global axes of each node's own sector) of a local pair force f_loc
    /// (t1, t2, n components, acting on the contact node): (A_cᴴ f_loc, A_tᴴ f_loc).
    fn pair_forces(&self, pair: &ContactPair, phi: f64, f_loc: [c64; 3]) -> ([c64; 3], [c64; 3]) {
        let a_c = self.contact_block(pair);
        let a_t = self.target_block(pair);
        let e = self.phase_factor(phi).conj();
        let mut f_c = [c64::new(0.0, 0.0); 3];
        let mut f_t = [c64::new(0.0, 0.0); 3];
        for k in 0..3 {
            for i in 0..3 {
                f_c[k] += f_loc[i] * a_c[i][k];
                f_t[k] += e * f_loc[i] * a_t[i][k];
            }
        }
        (f_c, f_t)
    }
}
