//! A `[[strip]]` on a mesh face group solved on the Craig–Bampton model of the mesh
//! (`[reduction]`; `src/problem/matrix_rom.rs`) against the same case solved unreduced, on the
//! bar damper's bar (1.25 m × 10 mm × 10 mm, clamped at x = 0, pads on z = 0 and z = a) meshed
//! with 20 × 1 × 4 hexahedra (`support/face_bar.rs`), so that the nodes at mid-height are interior
//! (600 free DOF; 258 masters on the pads and the tip, 60 fixed-interface modes):
//! * statically, a load on the tip gives the full model's displacement at every master DOF (the
//!   Craig–Bampton model is the exact static condensation on its masters);
//! * the forced response near the first axial resonance (1329.3 Hz) at H = 1 with the exact
//!   cycle: the tip's harmonics and every strip point's stick–slip map at four frequencies across
//!   the peak equal the unreduced ones (the difference is the truncation of the fixed-interface
//!   modes and the modal damping of the ROM's modes instead of the full model's: with 20, 60 and
//!   150 modes the tip differs by 3.1e-4, 5.6e-6 and 5.6e-6 of its amplitude,
//!   `cargo run --release --example strip_face_rom -- 20 1 4 MODES --full`);
//! * `nlrom march` on the reduced case follows the march of the unreduced one;
//! * rows that are interior DOF and settings a matrix case cannot reduce are keyed errors.

use std::path::Path;

use faer::linalg::solvers::Solve;
use faer::Mat;
use nlrom::case::Case;
use nlrom::march::march;
use nlrom::model;
use nlrom::problem::march_case::case_march;
use nlrom::problem::matrix_case::free_row_map;
use nlrom::problem::matrix_rom::reduced_matrix_model;

#[path = "support/face_bar.rs"]
mod face_bar;
use face_bar::{agreement, case_text, solve, HexBar};

/// The bar, with four elements over its height.
const BAR: HexBar = HexBar {
    length: 1.25,
    width: 0.01,
    height: 0.01,
    nx: 20,
    ny: 1,
    nz: 4,
};

/// The map frequencies (Hz): across the first axial resonance with the strip (1329.3 Hz).
const MAP_HZ: [f64; 4] = [1300.0, 1330.0, 1345.0, 1360.0];

/// The strip: the pads against rigid ground (no normal motion), the exact cycle at H = 1, maps
/// at [`MAP_HZ`].
const STRIP: &str = "face = \"pads\"\ndirection = [1.0, 0.0, 0.0]\nkt = 1.2e9\nmu = 0.3\npreload = 1000.0\nevaluation = \"analytic\"\nmap = 90\n";

/// The case on the mesh `mesh` with the face strip and `extra` tables.
fn case(dir: &Path, mesh: &Path, extra: &str) -> Case {
    let hz: Vec<String> = MAP_HZ.iter().map(|f| format!("{f:.1}")).collect();
    let tables = format!(
        "map_hz = [{}]\n\n[harmonic_balance]\nharmonics = 1\n\n[continuation]\nstart_hz = 1290.0\nend_hz = 1370.0\nstep_hz = 5.0\nmax_step_hz = 10.0\n{extra}",
        hz.join(", ")
    );
    Case::from_str(&case_text(mesh, STRIP, &tables), &dir.join("bar.toml")).unwrap()
}

fn mesh(dir: &Path) -> std::path::PathBuf {
    let path = dir.join("bar.msh");
    BAR.write(&path).unwrap();
    path
}

const MODES: usize = 60;
const REDUCTION: &str = "\n[reduction]\ninterface_modes = 60\n";

/// A static load on the tip (axial and transverse): the reduced model's displacement at every
/// master DOF equals the full model's to 1e-7 of the largest (measured 3.0e-9: the rounding of
/// the two dense solves, K of the slender clamped bar being ill-conditioned in bending).
#[test]
fn reduced_model_is_exact_statically_at_the_masters() {
    let dir = tempfile::tempdir().unwrap();
    let c = case(dir.path(), &mesh(dir.path()), REDUCTION);
    let full = model::build(&c, &mut |_| {}).unwrap();
    let rom = reduced_matrix_model(&c, full.clone(), &mut |_| {}).unwrap();
    let n_masters = rom
        .free
        .free_dofs
        .iter()
        .filter(|&&r| r < full.n_dofs)
        .count();
    assert_eq!(rom.free.n_free(), n_masters + MODES);
    assert!(full.free.n_free() > rom.free.n_free());
    // the x and z rows of the tip's nodes carry a load (case rows 3·node + component)
    let tip: Vec<usize> = (0..BAR.nodes())
        .filter(|i| i % (BAR.nx + 1) == BAR.nx)
        .flat_map(|i| [3 * i, 3 * i + 2])
        .collect();
    let solve = |m: &nlrom::model::StructuralModel| -> Vec<f64> {
        let free_of = free_row_map(m);
        let n = m.free.n_free();
        let mut f = Mat::<f64>::zeros(n, 1);
        for (k, &row) in tip.iter().enumerate() {
            f[(free_of[row].expect("tip row is free"), 0)] = 1.0 + 0.5 * k as f64;
        }
        let k = m.free.k.to_dense();
        let x = k.partial_piv_lu().solve(&f);
        (0..n).map(|i| x[(i, 0)]).collect()
    };
    let (x_full, x_rom) = (solve(&full), solve(&rom));
    let free_full = free_row_map(&full);
    let scale = x_full.iter().fold(0.0f64, |a, v| a.max(v.abs()));
    let mut worst: f64 = 0.0;
    for (r, &row) in rom.free.free_dofs.iter().enumerate().take(n_masters) {
        let i = free_full[row].unwrap();
        worst = worst.max((x_rom[r] - x_full[i]).abs() / scale);
    }
    eprintln!(
        "static tip load: {} free DOF → {} ROM coordinates, masters off the full model by {worst:.2e} of the largest displacement",
        full.free.n_free(),
        rom.free.n_free()
    );
    assert!(worst < 1e-7, "{worst:e}");
}

/// The forced response of the reduced and the unreduced case at the map frequencies: the tip's
/// harmonics within 2e-5 of their amplitude, the maps' transition angles within 1e-4 rad and no
/// sample in another state away from a transition (measured 5.6e-6, 1.3e-5 rad, none); some maps
/// have both stick and slip.
#[test]
fn reduced_face_strip_case_responds_as_the_unreduced_one() {
    let dir = tempfile::tempdir().unwrap();
    let m = mesh(dir.path());
    let full = solve(&case(dir.path(), &m, ""));
    let rom = solve(&case(dir.path(), &m, REDUCTION));
    assert_eq!(full.maps.len(), MAP_HZ.len());
    assert_eq!(rom.maps.len(), MAP_HZ.len());
    let agree = agreement(&rom, &full, 1, 1e-4);
    assert!(agree.harmonics < 2e-5, "{:e}", agree.harmonics);
    assert!(agree.angle < 1e-4, "{:e}", agree.angle);
    assert_eq!(agree.differ, 0);
    assert!(agree.mixed, "no map with both stick and slip");
}

/// The strip of the march: the time-discrete law of the same pads (no map, no `evaluation`).
const MARCH_STRIP: &str =
    "face = \"pads\"\ndirection = [1.0, 0.0, 0.0]\nkt = 1.2e9\nmu = 0.3\npreload = 1000.0\n";

/// `nlrom march` of the reduced and the unreduced case from rest at 1330 Hz (the case's scheme,
/// 64 steps a period, 3 periods) with the tip's axial load and response as rows (the march takes
/// `excitation.dofs`; `excitation.group` is a keyed error): the tip's displacement at every step
/// of the third period within 5e-3 of its largest value (measured 1.8e-3 with 60 modes; the
/// harmonic balance solutions agree to 5.6e-6: the march starts from rest, a transient that the
/// ROM's truncated modes and their modal damping carry less exactly than a steady response).
#[test]
fn reduced_face_strip_case_marches_as_the_unreduced_one() {
    let dir = tempfile::tempdir().unwrap();
    let m = mesh(dir.path());
    let tables = "\n[march]\nfrequency_hz = 1330.0\nperiods = 3\nsteps_per_period = 64\n";
    let text = |extra: &str| case_text(&m, MARCH_STRIP, &format!("{extra}{tables}"));
    let grouped = Case::from_str(&text(""), &dir.path().join("bar.toml")).unwrap();
    let msg = case_march(&grouped, None, &mut |_| {})
        .err()
        .unwrap()
        .to_string();
    assert!(
        msg.contains("excitation.group") && msg.contains("excitation.dofs"),
        "{msg}"
    );
    // the tip nodes' axial rows (3·node), 2 N in all
    let tip: Vec<usize> = (0..BAR.nodes())
        .filter(|i| i % (BAR.nx + 1) == BAR.nx)
        .map(|i| 3 * i)
        .collect();
    let rows = |r: &[usize]| {
        r.iter()
            .map(|d| d.to_string())
            .collect::<Vec<_>>()
            .join(", ")
    };
    let per = 2.0 / tip.len() as f64;
    let forces = vec![format!("{per:e}"); tip.len()].join(", ");
    let as_rows = |extra: &str| {
        text(extra)
            .replace(
                "group = \"tip\"\nforce = [2.0, 0.0, 0.0]",
                &format!("dofs = [{}]\nforce = [{forces}]", rows(&tip)),
            )
            .replace("groups = [\"tip\"]", &format!("dofs = [{}]", rows(&tip)))
    };
    let run = |extra: &str| {
        let c = Case::from_str(&as_rows(extra), &dir.path().join("bar.toml")).unwrap();
        let cm = case_march(&c, None, &mut |_| {}).unwrap();
        let out = march(&cm.system, &cm.settings).unwrap();
        (cm, out)
    };
    let (full_case, full) = run("");
    // the tip's rows are masters through `reduction.keep` (the group excitation made them so)
    let (rom_case, rom) = run(&format!("{REDUCTION}keep = [\"tip\"]\n"));
    assert!(rom_case.system.n < full_case.system.n);
    assert_eq!(full_case.response_dofs, rom_case.response_dofs);
    assert_eq!(full_case.response.len(), tip.len());
    let (nf, nr) = (full_case.system.n, rom_case.system.n);
    let steps = full.history.time.len();
    assert_eq!(steps, rom.history.time.len());
    let from = full.periods[full.periods.len() - 2].end_index;
    let (mut worst, mut scale) = (0.0f64, 0.0f64);
    for i in from..steps {
        for (&a, &b) in full_case.response.iter().zip(&rom_case.response) {
            let (x, y) = (full.history.q[i * nf + a], rom.history.q[i * nr + b]);
            scale = scale.max(x.abs());
            worst = worst.max((x - y).abs());
        }
    }
    eprintln!(
        "march at 1330 Hz: {nf} → {nr} DOF, tip off the unreduced march by {:.2e} of its largest displacement {scale:.3e} m",
        worst / scale
    );
    assert!(
        scale > 0.0 && worst < 5e-3 * scale,
        "{worst:e} of {scale:e}"
    );
}

/// Rows outside the masters and settings a matrix case cannot reduce are input errors naming
/// the key.
#[test]
fn reduction_errors_name_the_key() {
    let dir = tempfile::tempdir().unwrap();
    let m = mesh(dir.path());
    // a node at mid-height (k = 2) is interior: an [[element]] on its x row
    let interior = 3 * (5 + (BAR.nx + 1) * (BAR.ny + 1) * 2);
    let checks = [
        (
            format!("{REDUCTION}\n[[element]]\nkind = \"friction\"\ntangential = {{ dofs = [{interior}], weights = [1.0] }}\nkt = 1e6\nmu = 0.3\nn0 = 1.0\n"),
            vec!["element[0].tangential.dofs", "interior", "reduction.keep"],
        ),
        (
            format!("{REDUCTION}gsi_modes = 4\n"),
            vec!["reduction.gsi_modes"],
        ),
    ];
    for (extra, wanted) in checks {
        let c = case(dir.path(), &m, &extra);
        let full = model::build(&c, &mut |_| {}).unwrap();
        let msg = match reduced_matrix_model(&c, full, &mut |_| {}) {
            Ok(_) => panic!("no error for {extra}"),
            Err(e) => e.to_string(),
        };
        for w in wanted {
            assert!(msg.contains(w), "{w:?} not in: {msg}");
        }
    }
}
