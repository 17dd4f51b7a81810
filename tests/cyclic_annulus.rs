//! The definitive cyclic-symmetry test (`docs/theory.md`, "Cyclic symmetry"): the union
//! over k = 0..N−1 of the sector frequencies equals the frequencies of the full annulus — 8 rotated
//! copies of meshes/sector8.msh merged at the frontiers, assembled by nlrom as an ordinary model,
//! hub clamped — including multiplicities (k and N − k give the same frequencies: double modes).
//! Without CB (T_kᴴ K T_k on the sparse sector) to 1e-8, with CB to the CB accuracy. Also: the
//! properties of K_k (Hermitian, K_{N−k} = conj K_k, real k = 0, N/2), GSI, and bad input.

mod support;

use std::path::PathBuf;

use faer::{c64, Mat};
use nlrom::case::Case;
use nlrom::cyclic::{match_frontiers, CyclicGeometry};
use nlrom::eigen::hermitian_modes;
use nlrom::mesh::msh::read_msh;
use nlrom::model::{self, StructuralModel};
use nlrom::reduction::Sector;
use nlrom::Error;
use support::cyclic::{
    check_union_against_full, full_model_frequencies, max_rel_error, merge_sectors,
    sparse_sector_frequencies, union_below_cut,
};

const N: usize = 8;

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn case_text(cyclic_extra: &str, clamp: &str) -> String {
    format!(
        r#"
[model]
mesh = "../meshes/sector8.msh"
material = {{ young = 210e9, poisson = 0.3, density = 7800.0 }}
clamp = [{clamp}]

[cyclic]
sectors = {N}
low = "left_frontier"
high = "right_frontier"
{cyclic_extra}

[reduction]
interface_modes = 30
keep = ["excitation"]

[[contact]]
name = "shroud"
contact = "shroud_contact"
target = "shroud_target"
model = "node-to-node"
mu = 0.3
kt = 1.0e8
kn = 1.0e8
n0 = 100.0
"#
    )
}

fn load(text: &str) -> nlrom::Result<(Case, StructuralModel)> {
    let case = Case::from_str(text, &root().join("cases/test_annulus.toml"))?;
    let model = model::build(&case, &mut |_| {})?;
    Ok((case, model))
}

fn sector_case() -> (Case, StructuralModel) {
    load(&case_text("", "\"hub\"")).expect("sector case")
}

/// The lowest `n` annulus frequencies (Hz), hub clamped.
fn annulus_frequencies(n: usize) -> Vec<f64> {
    let sector = read_msh(&root().join("meshes/sector8.msh")).unwrap();
    let geom = CyclicGeometry::new(N, [0.0; 3], [0.0, 0.0, 1.0]).unwrap();
    let pairs = match_frontiers(&sector, &geom, "left_frontier", "right_frontier").unwrap();
    assert!(pairs.axis_nodes.is_empty());
    let mesh = merge_sectors(&sector, N, "left_frontier", "right_frontier", "hub");
    assert_eq!(mesh.num_nodes(), 11584); // meshes/README.md: frontiers merged only
    full_model_frequencies(&mesh, "hub", n)
}

fn fmt(v: &[f64]) -> String {
    v.iter()
        .map(|e| format!("{e:.1e}"))
        .collect::<Vec<_>>()
        .join(" ")
}

#[test]
fn union_of_sector_frequencies_is_the_annulus_spectrum() {
    let (case, model) = sector_case();
    let per_mode = 4;
    let sparse: Vec<Vec<f64>> = (0..N)
        .map(|k| sparse_sector_frequencies(&model, &case, k, per_mode))
        .collect();
    let (union, reference) =
        check_union_against_full(&sparse, annulus_frequencies, 20, "cs without CB");
    // k and N − k are conjugate: equal frequencies.
    for k in 1..N / 2 {
        assert!(max_rel_error(&sparse[k], &sparse[N - k]) < 1e-9, "k = {k}");
    }

    // With Craig–Bampton (30 interface modes).
    let sector = Sector::build(&case, &model, &mut |_| {}).unwrap();
    let cb: Vec<Vec<f64>> = (0..N)
        .map(|k| {
            let h = sector.harmonic(k, None).unwrap();
            hermitian_modes(h.stiffness.as_ref(), h.mass.as_ref(), h.real)
                .unwrap()
                .frequencies_hz(per_mode)
        })
        .collect();
    let per_k_err: Vec<f64> = (0..N).map(|k| max_rel_error(&cb[k], &sparse[k])).collect();
    println!(
        "CB+CS vs sparse cs, max relative error per k: {}",
        fmt(&per_k_err)
    );
    let union_cb = union_below_cut(&cb);
    assert_eq!(union_cb.len(), union.len());
    let err_cb = max_rel_error(&union_cb, &reference);
    println!("cs with CB (30 interface modes): max relative error {err_cb:.2e}");
    assert!(err_cb < 1e-3, "{err_cb:e}");
}

fn rel_norm(a: &Mat<c64>, b: &Mat<c64>) -> f64 {
    (a - b).norm_l2() / a.norm_l2()
}

#[test]
fn harmonic_matrices_are_hermitian_conjugate_pairs_and_real_at_0_and_half() {
    let (case, model) = sector_case();
    let sector = Sector::build(&case, &model, &mut |_| {}).unwrap();
    let hs: Vec<_> = (0..N).map(|k| sector.harmonic(k, None).unwrap()).collect();
    for h in &hs {
        for a in [&h.stiffness, &h.mass] {
            let herm = rel_norm(a, &a.adjoint().to_owned());
            assert!(herm <= 1e-12, "k = {}: {herm:e}", h.k);
        }
        // The high frontier is eliminated: 3 × 33 frontier nodes minus the clamped hub edge.
        assert!(h.dofs.len() < sector.cb.len());
    }
    for k in [0, N / 2] {
        assert!(hs[k].real);
        assert!(hs[k]
            .stiffness
            .col_iter()
            .all(|c| c.iter().all(|z| z.im == 0.0)));
        assert!(hs[k].mass.col_iter().all(|c| c.iter().all(|z| z.im == 0.0)));
    }
    for k in 1..N / 2 {
        assert!(!hs[k].real);
        let conj_k = hs[k].stiffness.conjugate().to_owned();
        let d = rel_norm(&hs[N - k].stiffness, &conj_k);
        assert!(d < 1e-13, "k = {k}: {d:e}");
        let conj_m = hs[k].mass.conjugate().to_owned();
        assert!(rel_norm(&hs[N - k].mass, &conj_m) < 1e-13);
        // Complex k really is complex.
        assert!(hs[k]
            .stiffness
            .col_iter()
            .any(|c| c.iter().any(|z| z.im != 0.0)));
    }
}

#[test]
fn gsi_reproduces_the_modes_used() {
    let (case, model) = sector_case();
    let sector = Sector::build(&case, &model, &mut |_| {}).unwrap();
    let n_g = 10;
    for k in [0, 2, 4] {
        let cs = sector.harmonic(k, None).unwrap();
        let g = sector.harmonic(k, Some(n_g)).unwrap();
        let report = g.gsi.clone().unwrap();
        assert_eq!(report.modes_used, n_g);
        assert_eq!(report.retained + report.dropped.len(), n_g);
        let f_cs = hermitian_modes(cs.stiffness.as_ref(), cs.mass.as_ref(), cs.real)
            .unwrap()
            .frequencies_hz(n_g + 10);
        let f_g = hermitian_modes(g.stiffness.as_ref(), g.mass.as_ref(), g.real)
            .unwrap()
            .frequencies_hz(n_g + 10);
        let used = max_rel_error(&f_g[..n_g], &f_cs[..n_g]);
        let next: Vec<f64> = f_g[n_g..]
            .iter()
            .zip(&f_cs[n_g..])
            .map(|(a, b)| a / b - 1.0)
            .collect();
        println!(
            "GSI k = {k}: {} coordinates → {} ({} interface vectors retained, dropped {:?}); modes 1–{n_g} max rel. error {used:.1e}; next 10: {}",
            cs.dofs.len(),
            g.dofs.len(),
            report.retained,
            report.dropped,
            fmt(&next)
        );
        assert!(used < 1e-10, "k = {k}: {used:e}");
        // Higher modes: Rayleigh–Ritz upper bounds of the CB+CS ones.
        assert!(next.iter().all(|&e| e > -1e-10), "{next:?}");
        if g.real {
            assert!(g
                .stiffness
                .col_iter()
                .all(|c| c.iter().all(|z| z.im == 0.0)));
        }
    }
}

fn input_error<T: std::fmt::Debug>(r: nlrom::Result<T>) -> String {
    match r {
        Err(Error::Input(msg)) => msg,
        other => panic!("expected an input error, got {other:?}"),
    }
}

#[test]
fn bad_cyclic_input_gives_clear_errors() {
    let (case, model) = sector_case();
    let sector = Sector::build(&case, &model, &mut |_| {}).unwrap();
    let msg = input_error(sector.harmonic(N, None));
    assert!(msg.contains("k = 8") && msg.contains("N = 8"), "{msg}");

    // Wrong sector count: the frontiers do not match under R_α.
    let text = case_text("", "\"hub\"").replace("sectors = 8", "sectors = 9");
    let (case9, model9) = load(&text).unwrap();
    let msg = input_error(Sector::build(&case9, &model9, &mut |_| {}));
    assert!(
        msg.contains("do not match") && msg.contains("left_frontier"),
        "{msg}"
    );

    // A clamp that fixes one frontier but not the other.
    let text = case_text("", "\"hub\", \"left_frontier\"");
    let (case_c, model_c) = load(&text).unwrap();
    let msg = input_error(Sector::build(&case_c, &model_c, &mut |_| {}));
    assert!(
        msg.contains("touches the clamp group 'left_frontier'"),
        "{msg}"
    );
}
