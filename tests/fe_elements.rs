//! FE assembly acceptance tests: patch tests, rigid-body modes, total mass, clamping and bad input.
//!
//! References are independent of the code under test: linear displacement fields (which every
//! element must reproduce exactly: constant strain), the rigid-body modes, closed-form volumes of
//! boxes and of the bundled Gmsh models, and a dense sum of element matrices.

use std::path::Path;

use faer::prelude::Solve;
use faer::sparse::SparseColMat;
use faer::{Mat, Side};
use nlrom::fe::structured::StructuredBox;
use nlrom::fe::{
    assemble, clamp, element_mass, element_stiffness, mesh_volume, rigid_body_modes, total_mass,
    Assembled, Material, Materials, Quadrature,
};
use nlrom::mesh::msh::read_msh;
use nlrom::mesh::{ElementType, Mesh};

// Every volume element type the assembly supports; structured boxes are built of each.
use nlrom::fe::shape::SUPPORTED as BOX_KINDS;

const STEEL: Material = Material {
    young: 210e9,
    poisson: 0.3,
    density: 7800.0,
};

fn bundled(name: &str) -> Mesh {
    read_msh(
        &Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("meshes")
            .join(name),
    )
    .unwrap()
}

fn assemble_uniform(mesh: &Mesh, material: Material) -> Assembled {
    assemble(mesh, &Materials::uniform(material), &Quadrature::default()).unwrap()
}

/// A distorted 3×3×3 box of `kind` (interior vertices moved by up to 20 % of the cell size).
fn distorted_box(kind: ElementType) -> Mesh {
    let mut b = StructuredBox::new(kind, [3, 3, 3], [1.0, 0.8, 1.2]).distorted(0.2, 42);
    b.origin = [0.1, -0.2, 0.3];
    b.build().unwrap()
}

/// y = A x for a CSC matrix.
fn spmv(a: &SparseColMat<usize, f64>, x: &[f64]) -> Vec<f64> {
    let sym = a.symbolic();
    let mut y = vec![0.0; a.nrows()];
    for (c, &xc) in x.iter().enumerate() {
        for p in sym.col_ptr()[c]..sym.col_ptr()[c + 1] {
            y[sym.row_idx()[p]] += a.val()[p] * xc;
        }
    }
    y
}

fn norm(v: &[f64]) -> f64 {
    v.iter().map(|x| x * x).sum::<f64>().sqrt()
}

fn frobenius(a: &SparseColMat<usize, f64>) -> f64 {
    norm(a.val())
}

/// The linear field u(x) = a + B x (B not symmetric: a strain and a small rotation).
fn linear_field(x: [f64; 3]) -> [f64; 3] {
    let a = [1e-3, -2e-3, 0.5e-3];
    let b = [
        [1e-3, 2e-4, -3e-4],
        [5e-4, -1e-3, 1e-4],
        [-2e-4, 3e-4, 7e-4],
    ];
    let mut u = a;
    for i in 0..3 {
        for k in 0..3 {
            u[i] += b[i][k] * x[k];
        }
    }
    u
}

/// Patch test: prescribe the linear field on the nodes of the bounding box's faces, solve
/// K_ii u_i = −K_ib u_b (dense Cholesky) and return the largest error of the interior
/// displacements relative to the largest displacement, and the number of interior nodes.
fn patch_test(mesh: &Mesh) -> (f64, usize) {
    let asm = assemble_uniform(mesh, STEEL);
    let [lo, hi] = mesh.bbox();
    let tol = 1e-9 * mesh.size();
    let on_boundary =
        |x: &[f64; 3]| (0..3).any(|k| (x[k] - lo[k]).abs() < tol || (x[k] - hi[k]).abs() < tol);
    let n = 3 * mesh.num_nodes();
    let (mut interior, mut boundary) = (Vec::new(), Vec::new());
    for (i, x) in mesh.coords.iter().enumerate() {
        let list = if on_boundary(x) {
            &mut boundary
        } else {
            &mut interior
        };
        list.extend((0..3).map(|c| 3 * i + c));
    }
    let exact: Vec<f64> = mesh.coords.iter().flat_map(|&x| linear_field(x)).collect();
    let mut ub = vec![0.0; n];
    for &d in &boundary {
        ub[d] = exact[d];
    }
    let k_ub = spmv(&asm.k, &ub);
    let kd = asm.k.to_dense();
    let kii = Mat::from_fn(interior.len(), interior.len(), |r, c| {
        kd[(interior[r], interior[c])]
    });
    let rhs = Mat::from_fn(interior.len(), 1, |r, _| -k_ub[interior[r]]);
    let x = kii
        .llt(Side::Lower)
        .expect("K_ii positive definite")
        .solve(&rhs);
    let scale = exact.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let err = interior
        .iter()
        .enumerate()
        .map(|(r, &d)| (x[(r, 0)] - exact[d]).abs())
        .fold(0.0, f64::max);
    (err / scale, interior.len() / 3)
}

#[test]
fn patch_test_reproduces_linear_fields_on_distorted_meshes() {
    for kind in BOX_KINDS {
        let (err, n_interior) = patch_test(&distorted_box(kind));
        eprintln!("patch {kind}: {n_interior} interior nodes, relative error {err:.1e}");
        assert!(n_interior >= 8, "{kind}: {n_interior} interior nodes");
        assert!(err < 1e-12, "{kind}: relative error {err:.2e}");
    }
}

#[test]
fn patch_test_on_mixed_gmsh_meshes_with_pyramids() {
    // hexa8 + prism6 + pyramid5 + tetra4, and hexa20 + prism15 + pyramid13 + tetra10.
    for name in ["mixed_o1.msh", "mixed_o2i.msh"] {
        let mesh = bundled(name);
        assert!(mesh
            .element_counts()
            .keys()
            .any(|k| k.first_order() == ElementType::Pyramid5));
        let (err, n_interior) = patch_test(&mesh);
        eprintln!("patch {name}: {n_interior} interior nodes, relative error {err:.1e}");
        assert!(n_interior >= 10, "{name}: {n_interior} interior nodes");
        assert!(err < 1e-12, "{name}: relative error {err:.2e}");
    }
}

#[test]
fn rigid_body_modes_are_in_the_null_space_of_k() {
    let mut meshes: Vec<(String, Mesh)> = BOX_KINDS
        .iter()
        .map(|&k| (k.to_string(), distorted_box(k)))
        .collect();
    for name in ["cube_tet10.msh", "mixed_o2i.msh", "sector_conforming.msh"] {
        meshes.push((name.to_string(), bundled(name)));
    }
    for (name, mesh) in &meshes {
        let asm = assemble_uniform(mesh, STEEL);
        let modes = rigid_body_modes(&mesh.coords, [0.3, -0.1, 0.2]);
        let kn = frobenius(&asm.k);
        for j in 0..6 {
            let r: Vec<f64> = (0..modes.nrows()).map(|i| modes[(i, j)]).collect();
            let rel = norm(&spmv(&asm.k, &r)) / (kn * norm(&r));
            eprintln!("rigid {name} mode {j}: {rel:.1e}");
            assert!(rel < 1e-10, "{name}: ‖K r{j}‖ / (‖K‖ ‖r{j}‖) = {rel:.2e}");
        }
        // And a non-rigid field is not: the test can fail.
        let stretch: Vec<f64> = mesh.coords.iter().flat_map(|x| [x[0], 0.0, 0.0]).collect();
        assert!(
            norm(&spmv(&asm.k, &stretch)) / (kn * norm(&stretch)) > 1e-6,
            "{name}"
        );
    }
}

#[test]
fn total_mass_is_density_times_volume() {
    let rho = 2700.0;
    let al = Material {
        young: 70e9,
        poisson: 0.33,
        density: rho,
    };
    let size = [1.0, 0.5, 2.0];
    for kind in BOX_KINDS {
        for distortion in [0.0, 0.2] {
            let mesh = StructuredBox::new(kind, [2, 3, 2], size)
                .distorted(distortion, 3)
                .build()
                .unwrap();
            let v = size.iter().product::<f64>();
            let m = total_mass(&assemble_uniform(&mesh, al).m);
            assert!(
                (m - rho * v).abs() < 1e-12 * rho * v,
                "{kind} distortion {distortion}: {m}"
            );
            let vq = mesh_volume(&mesh, &Quadrature::default()).unwrap();
            assert!((vq - v).abs() < 1e-12 * v, "{kind}: volume {vq}");
        }
    }
    // Bundled Gmsh models: bar 1 × 0.05 × 0.05, unit cube.
    for (name, v) in [
        ("bar_hex20.msh", 1.0 * 0.05 * 0.05),
        ("bar_tet10.msh", 1.0 * 0.05 * 0.05),
        ("cube_tet10.msh", 1.0),
        ("cube_tet4.msh", 1.0),
    ] {
        let mesh = bundled(name);
        let m = total_mass(&assemble_uniform(&mesh, al).m);
        assert!(
            (m - rho * v).abs() < 1e-12 * rho * v,
            "{name}: {m} vs {}",
            rho * v
        );
    }
}

#[test]
fn materials_by_volume_group() {
    // mixed_o1: hexes [0,1]³ (V = 1), prisms [1,2]×[0,1]² (V = 1), tets (with pyramids) on z ∈ [1,2] (V = 2).
    let mesh = bundled("mixed_o1.msh");
    let with = |density| Material { density, ..STEEL };
    let materials = Materials {
        default: Some(with(3000.0)),
        by_group: vec![
            ("hexes".into(), with(1000.0)),
            ("prisms".into(), with(2000.0)),
        ],
    };
    let asm = assemble(&mesh, &materials, &Quadrature::default()).unwrap();
    let expected = 1000.0 + 2000.0 + 2.0 * 3000.0;
    assert!(
        (total_mass(&asm.m) - expected).abs() < 1e-12 * expected,
        "{}",
        total_mass(&asm.m)
    );
}

#[test]
fn assembly_equals_the_dense_sum_of_element_matrices() {
    let mesh = bundled("mixed_o1.msh");
    let asm = assemble_uniform(&mesh, STEEL);
    let n = 3 * mesh.num_nodes();
    let mut k = Mat::<f64>::zeros(n, n);
    let mut m = Mat::<f64>::zeros(n, n);
    for block in mesh.blocks.iter().filter(|b| b.kind.dim() == 3) {
        for nodes in block.elements() {
            let xs: Vec<[f64; 3]> = nodes.iter().map(|&i| mesh.coords[i as usize]).collect();
            let ke = element_stiffness(block.kind, &xs, &STEEL, None).unwrap();
            let me = element_mass(block.kind, &xs, STEEL.density, None).unwrap();
            for r in 0..ke.nrows() {
                for c in 0..ke.ncols() {
                    let (gr, gc) = (
                        3 * nodes[r / 3] as usize + r % 3,
                        3 * nodes[c / 3] as usize + c % 3,
                    );
                    k[(gr, gc)] += ke[(r, c)];
                    m[(gr, gc)] += me[(r, c)];
                }
            }
        }
    }
    let (kd, md) = (asm.k.to_dense(), asm.m.to_dense());
    let (kmax, mmax) = (k.norm_max(), m.norm_max());
    for r in 0..n {
        for c in 0..n {
            assert!(
                (kd[(r, c)] - k[(r, c)]).abs() <= 1e-13 * kmax,
                "K[{r}][{c}]"
            );
            assert!(
                (md[(r, c)] - m[(r, c)]).abs() <= 1e-13 * mmax,
                "M[{r}][{c}]"
            );
            assert_eq!(kd[(r, c)], kd[(c, r)], "K symmetric");
        }
    }
}

#[test]
fn assembly_is_identical_for_any_thread_count() {
    let mesh = StructuredBox::new(ElementType::Tetra10, [4, 3, 3], [1.0, 1.0, 1.0])
        .distorted(0.15, 9)
        .build()
        .unwrap();
    let run = |threads| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        pool.install(|| assemble_uniform(&mesh, STEEL))
    };
    let (a, b) = (run(1), run(3));
    assert_eq!(a.k.val(), b.k.val());
    assert_eq!(a.m.val(), b.m.val());
    assert_eq!(a.k.symbolic().row_idx(), b.k.symbolic().row_idx());
}

#[test]
fn quadrature_override_matters_only_on_curved_elements() {
    // 4-point stiffness rule and a 64-point (degree 7) mass rule instead of 14 points for both.
    let low = Quadrature {
        stiffness_degree: Some(2),
        mass_degree: Some(6),
    };
    let rel_diff = |mesh: &Mesh| {
        let a = assemble_uniform(mesh, STEEL);
        let b = assemble(mesh, &Materials::uniform(STEEL), &low).unwrap();
        let d: Vec<f64> =
            a.k.val()
                .iter()
                .zip(b.k.val())
                .map(|(x, y)| x - y)
                .collect();
        let dm: Vec<f64> =
            a.m.val()
                .iter()
                .zip(b.m.val())
                .map(|(x, y)| x - y)
                .collect();
        (norm(&d) / frobenius(&a.k), norm(&dm) / frobenius(&a.m))
    };
    // Straight-sided tetra10: every rule of degree ≥ 2 (stiffness) and ≥ 4 (mass) is exact.
    let straight = distorted_box(ElementType::Tetra10);
    let (dk, dm) = rel_diff(&straight);
    assert!(dk < 1e-13 && dm < 1e-13, "straight: {dk:.2e} {dm:.2e}");
    // The sector's tetra10 are curved (mid-edge nodes on the geometry): the rules differ.
    let (dk, dm) = rel_diff(&bundled("sector_conforming.msh"));
    eprintln!("sector: 4- vs 14-point stiffness {dk:.2e}, 64- vs 14-point mass {dm:.2e}");
    assert!(dk > 1e-9 && dk < 1e-2, "curved stiffness: {dk:.2e}");
    assert!(dm > 1e-13 && dm < 1e-3, "curved mass: {dm:.2e}");
}

#[test]
fn clamping_eliminates_the_dofs_of_a_group() {
    let mesh = bundled("cube_tet10.msh");
    let asm = assemble_uniform(&mesh, STEEL);
    let bottom = mesh.nodes_of("bottom").unwrap();
    assert_eq!(bottom.len(), 65);
    let free = clamp(&asm, &mesh, &["bottom".to_string()]).unwrap();
    let n_free = 3 * (mesh.num_nodes() - 65);
    assert_eq!(free.n_free(), n_free);
    assert_eq!(
        (free.k.nrows(), free.k.ncols(), free.m.nrows()),
        (n_free, n_free, n_free)
    );
    // The DOF map: rows in order, no clamped node, components cycling x, y, z.
    let map = free.dof_map(&mesh);
    assert_eq!(map.len(), n_free);
    for (r, e) in map.entries.iter().enumerate() {
        assert_eq!(e.row, r);
        let i = mesh.node_index(e.node_tag).unwrap();
        assert!(
            bottom.binary_search(&i).is_err(),
            "clamped node {} in the map",
            e.node_tag
        );
        assert_eq!(3 * i as usize + e.component as usize, free.free_dofs[r]);
    }
    // K_ff and M_ff are the sub-matrices of K and M.
    let (kd, kf) = (asm.k.to_dense(), free.k.to_dense());
    let (md, mf) = (asm.m.to_dense(), free.m.to_dense());
    for (r, &gr) in free.free_dofs.iter().enumerate() {
        for (c, &gc) in free.free_dofs.iter().enumerate() {
            assert_eq!(kf[(r, c)], kd[(gr, gc)]);
            assert_eq!(mf[(r, c)], md[(gr, gc)]);
        }
    }
    // Clamped, the stiffness is positive definite; expand puts zeros back on the clamped DOF.
    assert!(kf.llt(Side::Lower).is_ok());
    let ones = vec![1.0; n_free];
    let full = free.expand(&ones, asm.n_dofs()).unwrap();
    assert_eq!(full.iter().filter(|&&v| v == 0.0).count(), 3 * 65);
    assert!(free.expand(&ones[1..], asm.n_dofs()).is_err());
}

#[test]
fn clamping_a_missing_group_is_an_error() {
    let mesh = bundled("cube_tet10.msh");
    let asm = assemble_uniform(&mesh, STEEL);
    let e = clamp(&asm, &mesh, &["bottom".into(), "base".into()]).unwrap_err();
    let s = e.to_string();
    assert!(
        s.contains("no physical group named 'base'") && s.contains("cube_tet10.msh"),
        "{s}"
    );
    assert_eq!(e.exit_code(), 2);
    // Matrices of another mesh.
    let other = StructuredBox::new(ElementType::Hexa8, [1, 1, 1], [1.0; 3])
        .build()
        .unwrap();
    assert!(clamp(&asm, &other, &["xmin".into()]).is_err());
}

fn input_error(r: nlrom::Result<Assembled>) -> String {
    let e = r.unwrap_err();
    assert_eq!(e.exit_code(), 2, "{e}");
    e.to_string()
}

#[test]
fn incompressible_material_is_an_error_naming_the_group() {
    let mesh = bundled("cube_tet10.msh");
    let bad = Material {
        poisson: 0.5,
        ..STEEL
    };
    let s = input_error(assemble(
        &mesh,
        &Materials {
            default: Some(STEEL),
            by_group: vec![("volume".into(), bad)],
        },
        &Quadrature::default(),
    ));
    assert!(s.contains("'volume'") && s.contains("poisson = 0.5"), "{s}");
    let s = input_error(assemble(
        &mesh,
        &Materials::uniform(bad),
        &Quadrature::default(),
    ));
    assert!(
        s.contains("default material") && s.contains("poisson = 0.5"),
        "{s}"
    );
}

#[test]
fn inverted_elements_are_errors_naming_the_tag_and_file() {
    // tetra4: swap two corners of the element with tag 5.
    let mut mesh = StructuredBox::new(ElementType::Tetra4, [2, 2, 2], [1.0; 3])
        .build()
        .unwrap();
    let b = &mut mesh.blocks[0];
    b.connectivity.swap(4 * 4 + 1, 4 * 4 + 2);
    let s = input_error(assemble(
        &mesh,
        &Materials::uniform(STEEL),
        &Quadrature::default(),
    ));
    assert!(
        s.contains("element 5 ") && s.contains("<structured tetra4 box 2x2x2>"),
        "{s}"
    );
    assert!(s.contains("non-positive Jacobian"), "{s}");
    // tetra10: the mirror image of element 12 (corners 1 ↔ 2 with their edges) and element 30.
    let mut mesh = StructuredBox::new(ElementType::Tetra10, [2, 2, 2], [1.0; 3])
        .build()
        .unwrap();
    for e in [29, 11] {
        let nodes = &mut mesh.blocks[0].connectivity[10 * e..10 * e + 10];
        nodes.swap(1, 2);
        nodes.swap(4, 6);
        nodes.swap(8, 9);
    }
    let s = input_error(assemble(
        &mesh,
        &Materials::uniform(STEEL),
        &Quadrature::default(),
    ));
    assert!(s.contains("element 12 ") && s.contains("1 more"), "{s}");
    assert!(mesh_volume(&mesh, &Quadrature::default())
        .unwrap_err()
        .to_string()
        .contains("element 12 "));
}

#[test]
fn missing_or_misplaced_materials_are_errors() {
    let mesh = bundled("mixed_o1.msh");
    let only_hexes = Materials {
        default: None,
        by_group: vec![("hexes".into(), STEEL)],
    };
    let s = input_error(assemble(&mesh, &only_hexes, &Quadrature::default()));
    assert!(
        s.contains("no material") && (s.contains("'prisms'") || s.contains("'tets'")),
        "{s}"
    );
    assert!(s.contains("mixed_o1.msh"), "{s}");
    let unknown = Materials {
        default: Some(STEEL),
        by_group: vec![("blade".into(), STEEL)],
    };
    let s = input_error(assemble(&mesh, &unknown, &Quadrature::default()));
    assert!(s.contains("'blade'"), "{s}");
    let surface = Materials {
        default: Some(STEEL),
        by_group: vec![("bottom".into(), STEEL)],
    };
    let s = input_error(assemble(&mesh, &surface, &Quadrature::default()));
    assert!(s.contains("'bottom'") && s.contains("dimension 2"), "{s}");
}

#[test]
fn unsupported_or_empty_meshes_are_errors() {
    // mixed_o2 holds pyramid14 elements (in group 'tets').
    let s = input_error(assemble(
        &bundled("mixed_o2.msh"),
        &Materials::uniform(STEEL),
        &Quadrature::default(),
    ));
    assert!(
        s.contains("pyramid14") && s.contains("'tets'") && s.contains("not supported"),
        "{s}"
    );
    // No volume elements at all.
    let mut mesh = bundled("cube_tet10.msh");
    mesh.blocks.retain(|b| b.kind.dim() < 3);
    let s = input_error(assemble(
        &mesh,
        &Materials::uniform(STEEL),
        &Quadrature::default(),
    ));
    assert!(s.contains("no volume"), "{s}");
    // A node index out of range (a hand-built mesh).
    let mut mesh = StructuredBox::new(ElementType::Hexa8, [1, 1, 1], [1.0; 3])
        .build()
        .unwrap();
    mesh.blocks[0].connectivity[3] = 99;
    let s = input_error(assemble(
        &mesh,
        &Materials::uniform(STEEL),
        &Quadrature::default(),
    ));
    assert!(s.contains("node index 99"), "{s}");
    // A quadrature degree out of range names the setting.
    let mesh = StructuredBox::new(ElementType::Hexa8, [1, 1, 1], [1.0; 3])
        .build()
        .unwrap();
    let q = Quadrature {
        stiffness_degree: Some(99),
        mass_degree: None,
    };
    let s = input_error(assemble(&mesh, &Materials::uniform(STEEL), &q));
    assert!(s.contains("stiffness_degree"), "{s}");
}
