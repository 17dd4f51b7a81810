//! Thermal and thermoelastic element matrices (src/fe/thermal.rs) against closed forms: capacity
//! total ρc_pV, conductance null space, the linear-temperature patch test, steady conduction of
//! a bar with a source, the decay rate of the first thermal mode, and free thermal expansion
//! (zero stress, strain α_th ΔT) — on every volume element type nlrom assembles (tetra4/10,
//! hexa8/20/27, prism6/15/18, pyramid5/13), on structured boxes, regular and distorted.

use faer::linalg::solvers::Solve;
use faer::Mat;
use nlrom::fe::structured::StructuredBox;
use nlrom::fe::thermal::{assemble_thermal, Capacity, ThermalAssembled, ThermalMaterial};
use nlrom::fe::{assemble, Material, Materials, Quadrature};
use nlrom::mesh::{ElementType, Mesh};

// Every volume element type the assembly supports; structured boxes are built of each.
use nlrom::fe::shape::SUPPORTED as BOX_KINDS;

const TI: Material = Material {
    young: 110e9,
    poisson: 0.3,
    density: 4430.0,
};
const TI_TH: ThermalMaterial = ThermalMaterial {
    conductivity: 6.7,
    specific_heat: 520.0,
    expansion: 9e-6,
    capacity: Capacity::Consistent,
};
const SIZE: [f64; 3] = [0.6, 0.2, 0.1];

fn quadratic(kind: ElementType) -> bool {
    kind.first_order() != kind
}

fn boxes(kind: ElementType, cells: [usize; 3]) -> Vec<(String, Mesh)> {
    let b = StructuredBox::new(kind, cells, SIZE);
    vec![
        ("regular".into(), b.clone().build().unwrap()),
        ("distorted".into(), b.distorted(0.2, 7).build().unwrap()),
    ]
}

/// The thermal matrices of `mesh` in titanium with the thermal data `th`, default quadrature.
fn thermal(mesh: &Mesh, th: &ThermalMaterial) -> ThermalAssembled {
    assemble_thermal(mesh, &Materials::uniform(TI), th, &Quadrature::default()).unwrap()
}

/// The dense titanium stiffness matrix K^uu of `mesh`, default quadrature.
fn stiffness(mesh: &Mesh) -> Mat<f64> {
    dense(
        &assemble(mesh, &Materials::uniform(TI), &Quadrature::default())
            .unwrap()
            .k,
    )
}

fn dense(a: &faer::sparse::SparseColMat<usize, f64>) -> Mat<f64> {
    a.to_dense()
}

fn matvec(a: &Mat<f64>, x: &[f64]) -> Vec<f64> {
    (0..a.nrows())
        .map(|i| (0..a.ncols()).map(|j| a[(i, j)] * x[j]).sum())
        .collect()
}

/// Solves A[free, free] x_free = b_free − A[free, fixed] x_fixed (dense LU).
fn solve_reduced(a: &Mat<f64>, b: &[f64], fixed: &[Option<f64>]) -> Vec<f64> {
    let free: Vec<usize> = (0..b.len()).filter(|&i| fixed[i].is_none()).collect();
    let xf: Vec<f64> = fixed.iter().map(|v| v.unwrap_or(0.0)).collect();
    let ax = matvec(a, &xf);
    let m = Mat::from_fn(free.len(), free.len(), |i, j| a[(free[i], free[j])]);
    let mut rhs = Mat::from_fn(free.len(), 1, |i, _| b[free[i]] - ax[free[i]]);
    let lu = m.partial_piv_lu();
    lu.solve_in_place(rhs.as_mut());
    let mut x = xf;
    for (k, &i) in free.iter().enumerate() {
        x[i] = rhs[(k, 0)];
    }
    x
}

#[test]
fn capacity_total_and_conductance_null_space() {
    let volume = SIZE.iter().product::<f64>();
    for kind in BOX_KINDS {
        for (what, mesh) in boxes(kind, [3, 2, 1]) {
            let t = thermal(&mesh, &TI_TH);
            let c = dense(&t.capacity);
            let k = dense(&t.conductance);
            let n = c.nrows();
            let ones = vec![1.0; n];
            let total: f64 = matvec(&c, &ones).iter().sum();
            let expected = TI.density * TI_TH.specific_heat * volume;
            assert!(
                (total - expected).abs() < 1e-12 * expected,
                "{kind} {what}: 1ᵀC1 = {total} vs ρcV = {expected}"
            );
            let scale = (0..n).map(|i| k[(i, i)]).fold(0.0, f64::max);
            let k1 = matvec(&k, &ones);
            assert!(
                k1.iter().all(|v| v.abs() < 1e-12 * scale),
                "{kind} {what}: K1 ≠ 0"
            );
            for i in 0..n {
                for j in 0..n {
                    assert!((k[(i, j)] - k[(j, i)]).abs() <= 1e-14 * scale);
                }
            }
            // Rigid translations and rotations are stress free: r_kᵀ K^uθ = 0.
            let ku = dense(&t.coupling);
            let kscale = ku.norm_max();
            for mode in 0..6 {
                let r: Vec<f64> = (0..3 * n)
                    .map(|p| {
                        let (node, comp) = (p / 3, p % 3);
                        let x = mesh.coords[node];
                        match mode {
                            0..=2 => (comp == mode) as u8 as f64,
                            _ => {
                                // ω × x for ω = e_(mode−3).
                                let w = mode - 3;
                                let (a, b) = ((w + 1) % 3, (w + 2) % 3);
                                if comp == a {
                                    -x[b]
                                } else if comp == b {
                                    x[a]
                                } else {
                                    0.0
                                }
                            }
                        }
                    })
                    .collect();
                for j in 0..n {
                    let v: f64 = (0..3 * n).map(|p| r[p] * ku[(p, j)]).sum();
                    assert!(v.abs() < 1e-11 * kscale, "{kind} {what}: mode {mode}: {v}");
                }
            }
        }
    }
}

#[test]
fn linear_temperature_patch_test() {
    // T = g x + 3: every row of K T is the boundary flux k g ∫ Nₐ n_x dS, zero off the end faces,
    // summing to ∓ k g A on x = 0 and x = L; with the ends prescribed, T is recovered exactly.
    let g = 40.0;
    let area = SIZE[1] * SIZE[2];
    for kind in BOX_KINDS {
        for (what, mesh) in boxes(kind, [3, 2, 2]) {
            let t = thermal(&mesh, &TI_TH);
            let k = dense(&t.conductance);
            let temp: Vec<f64> = mesh.coords.iter().map(|x| g * x[0] + 3.0).collect();
            let kt = matvec(&k, &temp);
            let (mut left, mut right) = (0.0, 0.0);
            for (i, x) in mesh.coords.iter().enumerate() {
                if x[0].abs() < 1e-12 {
                    left += kt[i];
                } else if (x[0] - SIZE[0]).abs() < 1e-12 {
                    right += kt[i];
                } else {
                    assert!(
                        kt[i].abs() < 1e-9 * TI_TH.conductivity * g * area,
                        "{kind} {what}: row {i}: {}",
                        kt[i]
                    );
                }
            }
            let flux = TI_TH.conductivity * g * area;
            assert!(
                (left + flux).abs() < 1e-10 * flux && (right - flux).abs() < 1e-10 * flux,
                "{kind} {what}: {left} {right}"
            );
            let fixed: Vec<Option<f64>> = mesh
                .coords
                .iter()
                .map(|x| {
                    let end = x[0].abs() < 1e-12 || (x[0] - SIZE[0]).abs() < 1e-12;
                    end.then_some(g * x[0] + 3.0)
                })
                .collect();
            let sol = solve_reduced(&k, &vec![0.0; temp.len()], &fixed);
            for (a, b) in sol.iter().zip(&temp) {
                assert!((a - b).abs() < 1e-10 * b.abs(), "{kind} {what}: {a} vs {b}");
            }
        }
    }
}

/// The largest nodal error, relative to the peak Q L²/(8k), of steady conduction with a uniform
/// source Q in the box of `kind` with `cells` cells, its ends x = 0 and x = L held at 0:
/// −k T'' = Q, T = Q x (L − x)/(2k), with the load f = ∫ Q Nₐ = (Q/ρc) C 1.
fn bar_conduction_error(kind: ElementType, cells: [usize; 3]) -> f64 {
    let (q, len) = (2.0e4, SIZE[0]);
    let mesh = StructuredBox::new(kind, cells, SIZE).build().unwrap();
    let t = thermal(&mesh, &TI_TH);
    let k = dense(&t.conductance);
    let c = dense(&t.capacity);
    let n = k.nrows();
    let rho_c = TI.density * TI_TH.specific_heat;
    let f: Vec<f64> = matvec(&c, &vec![1.0; n])
        .iter()
        .map(|v| v * q / rho_c)
        .collect();
    let fixed: Vec<Option<f64>> = mesh
        .coords
        .iter()
        .map(|x| (x[0].abs() < 1e-12 || (x[0] - len).abs() < 1e-12).then_some(0.0))
        .collect();
    let sol = solve_reduced(&k, &f, &fixed);
    let peak = q * len * len / (8.0 * TI_TH.conductivity);
    mesh.coords
        .iter()
        .zip(&sol)
        .map(|(x, v)| (v - q * x[0] * (len - x[0]) / (2.0 * TI_TH.conductivity)).abs())
        .fold(0.0, f64::max)
        / peak
}

#[test]
fn bar_conduction_with_a_source_matches_the_closed_form() {
    for kind in BOX_KINDS {
        if kind == ElementType::Pyramid5 {
            // The rational pyramid5 functions are not exact at the nodes: cubic cells of 0.1 m
            // and 0.05 m, the nodal error falls at second order.
            let (coarse, fine) = (
                bar_conduction_error(kind, [6, 2, 1]),
                bar_conduction_error(kind, [12, 4, 2]),
            );
            let order = (coarse / fine).log2();
            println!("{kind}: nodal error {coarse:.3e}, {fine:.3e}: order {order:.2}");
            assert!(order > 1.8, "{kind}: {coarse:.3e}, {fine:.3e}");
            continue;
        }
        // Quadratic elements reproduce the quadratic exactly; the linear ones are exact at the
        // nodes of this one-cell-thick mesh (the 1-D nodal exactness of linear elements).
        let worst = bar_conduction_error(kind, [6, 1, 1]);
        assert!(worst < 1e-10, "{kind}: {worst}");
    }
}

#[test]
fn first_thermal_mode_decays_at_kappa_pi_over_l_squared() {
    // Insulated bar: the lowest non-zero eigenvalue of (K^θθ, C^θθ) ≈ κ(π/L)², from above
    // (consistent capacity), converging with the mesh.
    let kappa = TI_TH.conductivity / (TI.density * TI_TH.specific_heat);
    let exact = kappa * (std::f64::consts::PI / SIZE[0]).powi(2);
    for kind in BOX_KINDS {
        let mut errs = Vec::new();
        for cells in [4, 8] {
            let mesh = StructuredBox::new(kind, [cells, 1, 1], SIZE)
                .build()
                .unwrap();
            let t = thermal(&mesh, &TI_TH);
            let (k, c) = (dense(&t.conductance), dense(&t.capacity));
            // C = L Lᵀ, eigenvalues of L⁻¹ K L⁻ᵀ.
            let l = c.llt(faer::Side::Lower).unwrap().L().to_owned();
            let mut x = k.clone();
            faer::linalg::triangular_solve::solve_lower_triangular_in_place(
                l.as_ref(),
                x.as_mut(),
                faer::Par::Seq,
            );
            let mut y = x.transpose().to_owned();
            faer::linalg::triangular_solve::solve_lower_triangular_in_place(
                l.as_ref(),
                y.as_mut(),
                faer::Par::Seq,
            );
            let sym = Mat::from_fn(y.nrows(), y.nrows(), |i, j| 0.5 * (y[(i, j)] + y[(j, i)]));
            let (mut ev, _) = nlrom::eigen::self_adjoint_eigen_qr(sym.as_ref()).unwrap();
            ev.sort_by(f64::total_cmp);
            assert!(ev[0].abs() < 1e-9 * ev[1], "{kind}: the constant mode");
            let mu1 = ev[1];
            assert!(mu1 >= exact * (1.0 - 1e-12), "{kind}: {mu1} below {exact}");
            errs.push((mu1 - exact) / exact);
        }
        println!("{kind}: first decay rate error {errs:?}");
        let order = (errs[0] / errs[1]).log2();
        let expected = if quadratic(kind) { 4.0 } else { 2.0 };
        assert!(
            (order - expected).abs() < 0.3,
            "{kind}: order {order} ({errs:?})"
        );
    }
}

#[test]
fn free_thermal_expansion_is_stress_free() {
    // Uniform ΔT on a body held by a 3-2-1 support at the origin corner: K u = −K^uθ θ gives
    // u = α_th ΔT x exactly (zero stress), on regular and distorted meshes.
    let dt = 150.0;
    for kind in BOX_KINDS {
        for (what, mesh) in boxes(kind, [2, 2, 1]) {
            let k = stiffness(&mesh);
            let t = thermal(&mesh, &TI_TH);
            let ku = dense(&t.coupling);
            let n = mesh.coords.len();
            let f: Vec<f64> = matvec(&ku, &vec![dt; n]).iter().map(|v| -v).collect();
            let find = |p: [f64; 3]| {
                mesh.coords
                    .iter()
                    .position(|x| (0..3).all(|c| (x[c] - p[c]).abs() < 1e-12))
                    .unwrap()
            };
            let (o, a, b) = (
                find([0.0; 3]),
                find([SIZE[0], 0.0, 0.0]),
                find([0.0, SIZE[1], 0.0]),
            );
            let mut fixed = vec![None; 3 * n];
            for c in 0..3 {
                fixed[3 * o + c] = Some(0.0);
            }
            fixed[3 * a + 1] = Some(0.0);
            fixed[3 * a + 2] = Some(0.0);
            fixed[3 * b + 2] = Some(0.0);
            let u = solve_reduced(&k, &f, &fixed);
            let scale = TI_TH.expansion * dt * SIZE[0];
            let worst = (0..3 * n)
                .map(|p| (u[p] - TI_TH.expansion * dt * mesh.coords[p / 3][p % 3]).abs())
                .fold(0.0, f64::max);
            assert!(
                worst < 1e-9 * scale,
                "{kind} {what}: {worst:.3e} of {scale:.3e}"
            );
        }
    }
}

#[test]
fn clamped_bar_tip_moves_outward_by_alpha_delta_t_length() {
    // Sign: the face x = 0 held axially (u_x = 0, one point fully), uniform ΔT > 0: the far end
    // moves by +α ΔT L.
    let dt = 80.0;
    let mesh = StructuredBox::new(ElementType::Hexa20, [4, 1, 1], SIZE)
        .build()
        .unwrap();
    let k = stiffness(&mesh);
    let t = thermal(&mesh, &TI_TH);
    let n = mesh.coords.len();
    let f: Vec<f64> = matvec(&dense(&t.coupling), &vec![dt; n])
        .iter()
        .map(|v| -v)
        .collect();
    let mut fixed = vec![None; 3 * n];
    for (i, x) in mesh.coords.iter().enumerate() {
        if x[0].abs() < 1e-12 {
            fixed[3 * i] = Some(0.0);
            if x[1].abs() < 1e-12 && x[2].abs() < 1e-12 {
                fixed[3 * i + 1] = Some(0.0);
                fixed[3 * i + 2] = Some(0.0);
            }
            if (x[1] - SIZE[1]).abs() < 1e-12 && x[2].abs() < 1e-12 {
                fixed[3 * i + 2] = Some(0.0);
            }
        }
    }
    let u = solve_reduced(&k, &f, &fixed);
    for (i, x) in mesh.coords.iter().enumerate() {
        if (x[0] - SIZE[0]).abs() < 1e-12 {
            let expected = TI_TH.expansion * dt * SIZE[0];
            assert!(
                (u[3 * i] - expected).abs() < 1e-9 * expected,
                "{}",
                u[3 * i]
            );
        }
    }
}

#[test]
fn lumped_capacity_is_a_positive_diagonal_with_the_total_and_the_hrz_shares() {
    // HRZ lumping (Hinton, Rock & Zienkiewicz 1976): diagonal, positive at every node (the row
    // sums of the serendipity types are negative at their vertices), total ρc_pV. On one cubic
    // hexa20 cell the shares are ∫N²/Σ∫N² from the reference-cube integrals ∫N² = 28/135 at a
    // vertex and 64/135 at a mid-edge node: 7/248 and 2/31 of ρc_pV.
    let lumped = ThermalMaterial {
        capacity: Capacity::Lumped,
        ..TI_TH
    };
    let volume = SIZE.iter().product::<f64>();
    let rho_c = TI.density * TI_TH.specific_heat;
    for kind in BOX_KINDS {
        for (what, mesh) in boxes(kind, [3, 2, 1]) {
            let t = thermal(&mesh, &lumped);
            let c = dense(&t.capacity);
            let n = c.nrows();
            let mut total = 0.0;
            for i in 0..n {
                assert!(c[(i, i)] > 0.0, "{kind} {what}: C_{i}{i} = {}", c[(i, i)]);
                total += c[(i, i)];
                for j in (0..n).filter(|&j| j != i) {
                    assert_eq!(c[(i, j)], 0.0, "{kind} {what}");
                }
            }
            assert!(
                (total - rho_c * volume).abs() < 1e-12 * rho_c * volume,
                "{kind} {what}: {total} vs {}",
                rho_c * volume
            );
        }
    }
    let side = 0.01;
    let mesh = StructuredBox::new(ElementType::Hexa20, [1, 1, 1], [side; 3])
        .build()
        .unwrap();
    let t = thermal(&mesh, &lumped);
    let c = dense(&t.capacity);
    let total = rho_c * side.powi(3);
    let (mut vertices, mut edges) = (0, 0);
    for (i, x) in mesh.coords.iter().enumerate() {
        let on_edge = x
            .iter()
            .filter(|&&v| (v - side / 2.0).abs() < 1e-12)
            .count()
            == 1;
        let share = if on_edge { 2.0 / 31.0 } else { 7.0 / 248.0 };
        if on_edge {
            edges += 1;
        } else {
            vertices += 1;
        }
        assert!(
            (c[(i, i)] - share * total).abs() < 1e-12 * total,
            "node {i} at {x:?}: {} vs {}",
            c[(i, i)],
            share * total
        );
    }
    assert_eq!((vertices, edges), (8, 12));
}

#[test]
fn invalid_thermal_data_is_an_error_naming_the_key() {
    let mesh = StructuredBox::new(ElementType::Hexa8, [1, 1, 1], SIZE)
        .build()
        .unwrap();
    let bad = ThermalMaterial {
        specific_heat: 0.0,
        ..TI_TH
    };
    let e =
        assemble_thermal(&mesh, &Materials::uniform(TI), &bad, &Quadrature::default()).unwrap_err();
    assert!(e.to_string().contains("specific_heat"), "{e}");
    let bad = ThermalMaterial {
        conductivity: -1.0,
        ..TI_TH
    };
    let e =
        assemble_thermal(&mesh, &Materials::uniform(TI), &bad, &Quadrature::default()).unwrap_err();
    assert!(e.to_string().contains("conductivity"), "{e}");
}

#[test]
fn mixed_meshes_with_pyramids_pass_the_patch_and_expansion_tests() {
    // meshes/mixed_o1.msh (tetra4, hexa8, prism6, pyramid5) and mixed_o2i.msh (tetra10, hexa20,
    // prism15, pyramid13), curved-free unit-scale geometry.
    for name in ["mixed_o1", "mixed_o2i"] {
        let path =
            std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR")).join(format!("meshes/{name}.msh"));
        let mesh = nlrom::mesh::msh::read_msh(&path).unwrap();
        let t = thermal(&mesh, &TI_TH);
        let (k, c) = (dense(&t.conductance), dense(&t.capacity));
        let n = mesh.coords.len();
        let volume = nlrom::fe::mesh_volume(&mesh, &Quadrature::default()).unwrap();
        let total: f64 = matvec(&c, &vec![1.0; n]).iter().sum();
        let expected = TI.density * TI_TH.specific_heat * volume;
        assert!(
            (total - expected).abs() < 1e-12 * expected,
            "{name}: {total} vs {expected}"
        );
        // Linear T = g·x: TᵀK T = k |g|² V (Σₐ xₐ ∇Nₐ = I), and K 1 = 0.
        let g = [3.0, -2.0, 5.0];
        let temp: Vec<f64> = mesh
            .coords
            .iter()
            .map(|x| g[0] * x[0] + g[1] * x[1] + g[2] * x[2])
            .collect();
        let ktt: f64 = matvec(&k, &temp)
            .iter()
            .zip(&temp)
            .map(|(a, b)| a * b)
            .sum();
        let exact = TI_TH.conductivity * 38.0 * volume;
        assert!(
            (ktt - exact).abs() < 1e-11 * exact,
            "{name}: {ktt} vs {exact}"
        );
        let scale = (0..n).map(|i| k[(i, i)]).fold(0.0, f64::max);
        assert!(matvec(&k, &vec![1.0; n])
            .iter()
            .all(|v| v.abs() < 1e-12 * scale));
        // Free expansion; the nine DOF of three nodes spanning the body set to the exact field.
        let dt = 50.0;
        let kk = stiffness(&mesh);
        let f: Vec<f64> = matvec(&dense(&t.coupling), &vec![dt; n])
            .iter()
            .map(|v| -v)
            .collect();
        let x0 = mesh.coords[0];
        let exact_u = |p: usize| TI_TH.expansion * dt * (mesh.coords[p / 3][p % 3] - x0[p % 3]);
        // The node farthest from node 0, and the one farthest from the line through both.
        let far = (0..n)
            .max_by(|&a, &b| {
                let d = |i: usize| {
                    (0..3)
                        .map(|c| (mesh.coords[i][c] - x0[c]).powi(2))
                        .sum::<f64>()
                };
                d(a).total_cmp(&d(b))
            })
            .unwrap();
        let third = (0..n)
            .max_by(|&a, &b| {
                let d = |i: usize| {
                    let (u, v): (Vec<f64>, Vec<f64>) = (0..3)
                        .map(|c| (mesh.coords[far][c] - x0[c], mesh.coords[i][c] - x0[c]))
                        .unzip();
                    let cross = [
                        u[1] * v[2] - u[2] * v[1],
                        u[2] * v[0] - u[0] * v[2],
                        u[0] * v[1] - u[1] * v[0],
                    ];
                    cross.iter().map(|z| z * z).sum::<f64>()
                };
                d(a).total_cmp(&d(b))
            })
            .unwrap();
        let mut fixed = vec![None; 3 * n];
        for p in [
            0,
            1,
            2,
            3 * far,
            3 * far + 1,
            3 * far + 2,
            3 * third,
            3 * third + 1,
            3 * third + 2,
        ] {
            fixed[p] = Some(exact_u(p));
        }
        let u = solve_reduced(&kk, &f, &fixed);
        let worst = (0..3 * n)
            .map(|p| (u[p] - exact_u(p)).abs())
            .fold(0.0, f64::max);
        let scale = TI_TH.expansion * dt;
        assert!(worst < 1e-9 * scale, "{name}: {worst:.3e}");
    }
}
