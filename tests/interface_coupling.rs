//! SAMA's interpolated coupling in the harmonic balance (`coupling = "interpolated"`, Battiato
//! 2021 §4 Fig. 8) on the bundled non-conforming shroud (N = 24, k = 3): in the stuck limit the
//! HB response equals the ROM plus linear springs on r = u_c − e^{iσφ_k} R_α^σ Σ_j N_j u_tj
//! assembled here independently from the interface's weights, and the coupling is stiffer than
//! that by the array's spurious stiffness when the array is used instead.

mod support;

use std::path::Path;

use faer::linalg::solvers::Solve;
use faer::{c64, Mat};
use nlrom::case::{Case, SamaCoupling};
use nlrom::cyclic::phase;
use nlrom::harmonics::HarmonicForce;
use nlrom::interface::{build_interfaces, ContactInterface};
use nlrom::model;
use nlrom::output::ContactData;
use nlrom::problem::sector::SectorProblem;
use nlrom::reduction::reduce;
use nlrom::rom::{HarmonicRom, Rom};

use support::sector_hb::hb_outputs;

/// The case with the interpolated coupling, μ = 1e6 (never slips), n0 = 1e6 N (the smallest
/// node's share, ≈ 2e3 N, keeps it closed: k_n × the relative motion is far below) and H = 1.
fn case() -> Case {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("cases/shroud_nonconforming.toml");
    let mut case = Case::load(&path).unwrap();
    case.contact[0].coupling = Some(SamaCoupling::Interpolated);
    case.contact[0].mu = 1e6;
    case.contact[0].n0 = 1e6;
    case.harmonic_balance.harmonics = 1;
    case
}

/// Stiffness of every contact node's spring (k_t, k_t, k_n in its frame) on
/// r = u_c − e^{iσφ_k} R^σ Σ_j w_j u_tj, in the ROM coordinates of k (pairs' weights as
/// interpolation coefficients: for the interpolated coupling, the element of each node).
fn interpolated_springs(
    h: &HarmonicRom,
    iface: &ContactInterface,
    rom: &Rom,
    k: usize,
) -> Mat<c64> {
    let geom = rom.cyclic.unwrap();
    let rot = geom.rotation(iface.sigma);
    let e = c64::from_polar(1.0, iface.sigma as f64 * phase(k, geom.sectors));
    let mut kc = Mat::<c64>::zeros(h.len(), h.len());
    for p in &iface.pairs {
        let f = p.frame;
        let stiff = [
            p.kt.iter().sum::<f64>(),
            p.kt.iter().sum(),
            p.kn.iter().sum(),
        ];
        let g = |a: usize, b: usize| (0..3).map(|l| f[l][a] * stiff[l] * f[l][b]).sum::<f64>();
        // L: (ROM row, the 3 global components of r it contributes to).
        let mut l: Vec<(usize, [c64; 3])> = Vec::new();
        for d in 0..3 {
            let mut col = [c64::new(0.0, 0.0); 3];
            col[d] = c64::new(1.0, 0.0);
            l.push((h.row_of(p.contact_node, d as u8).unwrap(), col));
            for (&t, &w) in p.targets.iter().zip(&p.weights) {
                let col = [0, 1, 2].map(|a| -e * w * rot[a][d]);
                l.push((h.row_of(t, d as u8).unwrap(), col));
            }
        }
        support::springs::add_spring(&mut kc, &l, g);
    }
    kc
}

/// Direct solve of (K − ω²M + iωC + K_c) Q = F on the ROM of k, at the problem's outputs.
fn rom_solve(
    h: &HarmonicRom,
    problem: &SectorProblem,
    case: &Case,
    omega: f64,
    kc: &Mat<c64>,
) -> Vec<c64> {
    let c = h.damping.as_ref().unwrap();
    let d = Mat::from_fn(h.len(), h.len(), |i, j| {
        h.stiffness[(i, j)] - h.mass[(i, j)] * (omega * omega)
            + c[(i, j)] * c64::new(0.0, omega)
            + kc[(i, j)]
    });
    let ex = case.excitation.as_ref().unwrap();
    let force = match &ex.load {
        nlrom::case::ExcitationLoad::Group { force, .. } => *force,
        _ => unreachable!(),
    };
    let mut f = Mat::<c64>::zeros(h.len(), 1);
    for o in problem.outputs.iter() {
        f[(h.row_of(o.node_tag, o.component).unwrap(), 0)] +=
            c64::new(force[o.component as usize], 0.0);
    }
    let q = d.partial_piv_lu().solve(&f);
    problem
        .outputs
        .iter()
        .map(|o| q[(h.row_of(o.node_tag, o.component).unwrap(), 0)])
        .collect()
}

fn rel_err(a: &[c64], b: &[c64]) -> f64 {
    let d: f64 = a.iter().zip(b).map(|(x, y)| (x - y).norm_sqr()).sum();
    let n: f64 = b.iter().map(|y| y.norm_sqr()).sum();
    (d / n).sqrt()
}

/// Stuck limit of the interpolated coupling: the HB harmonic 1 at 760 Hz (below the stuck
/// resonance, 787 Hz) equals the ROM + the independently assembled interpolated springs to 1e-8
/// (the virtual-node rows, the LinearMap's forces Bᵀ F_y and Jacobian Bᵀ J_y B, the preload
/// balance), and differs from the array coupling's response (stiffer, 911 Hz) by far more.
#[test]
fn interpolated_stuck_limit_equals_rom_with_interpolated_springs() {
    let case = case();
    let model = model::build(&case, &mut |_| {}).unwrap();
    let rom = reduce(&case, &model, &mut |_| {}).unwrap();
    let mesh = model.mesh.as_ref().unwrap();
    let interfaces = build_interfaces(&case, mesh, rom.cyclic.as_ref()).unwrap();
    let problem = SectorProblem::build(&case, &rom, mesh, &interfaces).unwrap();
    // 65 elements (one per contact node) on 65 contact + the target nodes' rows, through the map
    assert_eq!(problem.contact.inner.pairs().len(), 65);
    assert_eq!(problem.contact.n_dofs(), problem.nonlinear.len());
    let k = problem.harmonic_indices[1];
    let h = rom.harmonic(k).unwrap();
    let omega = 2.0 * std::f64::consts::PI * 760.0;
    let hb = hb_outputs(&problem, omega);
    let kc = interpolated_springs(h, &interfaces[0], &rom, k);
    let direct = rom_solve(h, &problem, &case, omega, &kc);
    let err = rel_err(&hb, &direct);
    let mut array_case = case.clone();
    array_case.contact[0].coupling = Some(SamaCoupling::Array);
    let array_ifaces = build_interfaces(&array_case, mesh, rom.cyclic.as_ref()).unwrap();
    let array = SectorProblem::build(&array_case, &rom, mesh, &array_ifaces).unwrap();
    // the results file lists the harmonic balance's elements, one row each, for both couplings
    for (iface, prob) in [(&interfaces[0], &problem), (&array_ifaces[0], &array)] {
        let data = ContactData::from_interface(iface);
        assert_eq!(data.pairs.len(), prob.contact.inner.pairs().len());
        assert_eq!(data.pairs.len(), iface.element_count());
        let kt: f64 = data.pairs.iter().map(|p| p.kt).sum();
        let total: f64 = iface.pairs.iter().flat_map(|p| p.kt.iter()).sum();
        assert!(
            (kt - total).abs() <= 1e-12 * total,
            "{} {kt} {total}",
            data.coupling
        );
    }
    let other = rel_err(&hb_outputs(&array, omega), &direct);
    println!("interpolated HB vs ROM + springs: {err:.2e}; array coupling differs by {other:.2e}");
    assert!(err < 1e-8, "{err:.3e}");
    assert!(other > 0.1, "{other:.3e}");
}

/// The LinearMap's forward map, transpose and Jacobian against the dense B built from the same
/// combinations (identity on the outer DOFs, then the extra rows), H = 2.
#[test]
fn dof_map_matches_the_dense_matrix() {
    use nlrom::contact::aft::global_index;
    use nlrom::contact::mapped::LinearMap;
    use nlrom::harmonics::HarmonicLayout;
    let layout = HarmonicLayout::new(2, 16).unwrap();
    let extra = vec![vec![(0, 0.25), (2, -0.5)], vec![(1, 2.0)]];
    let map = LinearMap::identity_and(3, extra.clone()).unwrap();
    let (no, ni, m) = (3, 5, layout.coefficients());
    assert_eq!((map.outer(), map.inner()), (no, ni));
    let rows: Vec<Vec<(usize, f64)>> = (0..no).map(|s| vec![(s, 1.0)]).chain(extra).collect();
    let mut b = Mat::<f64>::zeros(ni * m, no * m);
    for l in 0..m {
        for (r, row) in rows.iter().enumerate() {
            for &(s, c) in row {
                b[(
                    global_index(&layout, l, r, ni),
                    global_index(&layout, l, s, no),
                )] += c;
            }
        }
    }
    let x: Vec<f64> = (0..no * m).map(|i| (i as f64 * 0.7).sin()).collect();
    let y = map.forward(&layout, &x);
    let yd = &b * Mat::from_fn(no * m, 1, |i, _| x[i]);
    for i in 0..ni * m {
        assert!((y[i] - yd[(i, 0)]).abs() < 1e-15);
    }
    let mut back = vec![1.0; no * m];
    map.add_transpose(&layout, &y, &mut back);
    let bd = b.transpose() * &yd;
    for i in 0..no * m {
        assert!((back[i] - 1.0 - bd[(i, 0)]).abs() < 1e-14);
    }
    let jy = Mat::from_fn(ni * m, ni * m, |i, j| ((i * 31 + j * 7) % 13) as f64 - 6.0);
    let mut jx = Mat::<f64>::zeros(no * m, no * m);
    map.add_jacobian(&layout, jy.as_ref(), jx.as_mut());
    let jd = b.transpose() * &jy * &b;
    for i in 0..no * m {
        for j in 0..no * m {
            assert!((jx[(i, j)] - jd[(i, j)]).abs() < 1e-12);
        }
    }
    assert!(LinearMap::identity_and(2, vec![vec![(2, 1.0)]]).is_err());
    assert!(LinearMap::identity_and(2, vec![vec![(0, f64::NAN)]]).is_err());
}
