//! Fully stuck natural frequencies of a shroud case for the SAMA couplings (issue 8 diagnosis).
//!
//!     cargo run --release --example stuck_frequencies -- CASE.toml [KT_SCALE]
//!
//! The ROM of the excitation's harmonic index k_1 plus linear springs (k_t, k_t, k_n per contact
//! node, times KT_SCALE, default 1) on the contact pairs of the case's first `[[contact]]`,
//! assembled here independently of the harmonic balance: r = u_c − e^{iσφ_k} R_α^σ Σ_j w_j u_tj.
//! Printed: the generalized eigenfrequencies (Hz) below 1.5 kHz of (K + K_c, M) for
//! - `free`: no contact;
//! - `array`: SAMA's parallel pairs c–t_j with k_tj = w_j k_t (eq 31; node-to-node when w = 1);
//! - `idw-interpolated`: one spring per node on u_c − Σ_j w_j u_tj with the inverse-distance w_j;
//! - `shape-interpolated`: one spring per node on u_c − Σ_j N_j u_tj (`coupling = "interpolated"`).

use std::path::Path;

use faer::{c64, Mat};
use nlrom::case::{Case, SamaCoupling};
use nlrom::cyclic::phase;
use nlrom::eigen::self_adjoint_eigen_qr;
use nlrom::error::Result;
use nlrom::model;
use nlrom::reduction::reduce;
use nlrom::rom::HarmonicRom;
use nlrom::sama::{build_interfaces, ContactInterface};

/// One spring: r = Σ (node tag, coefficient, is_target) with diag(k_t, k_t, k_n) in `frame`.
struct Spring {
    terms: Vec<(u64, f64, bool)>,
    frame: [[f64; 3]; 3],
    stiffness: [f64; 3],
}

/// The springs of `iface`: one per pair c–t_j (`parallel`) or one per contact node on the
/// weighted combination of its targets.
fn springs(iface: &ContactInterface, parallel: bool, scale: f64) -> Vec<Spring> {
    let mut out = Vec::new();
    for p in &iface.pairs {
        let contact = (p.contact_node, 1.0, false);
        if parallel {
            for (j, &t) in p.targets.iter().enumerate() {
                out.push(Spring {
                    terms: vec![contact, (t, 1.0, true)],
                    frame: p.frame,
                    stiffness: [p.kt[j], p.kt[j], p.kn[j]].map(|k| k * scale),
                });
            }
        } else {
            let mut terms = vec![contact];
            terms.extend(
                p.targets
                    .iter()
                    .zip(&p.weights)
                    .map(|(&t, &w)| (t, w, true)),
            );
            let kt: f64 = p.kt.iter().sum();
            let kn: f64 = p.kn.iter().sum();
            out.push(Spring {
                terms,
                frame: p.frame,
                stiffness: [kt, kt, kn].map(|k| k * scale),
            });
        }
    }
    out
}

/// K_c = Lᴴ Fᵀ diag(k) F L in the ROM coordinates of h (target terms −e R^σ).
fn assemble(h: &HarmonicRom, springs: &[Spring], e: c64, rot: [[f64; 3]; 3]) -> Mat<c64> {
    let mut kc = Mat::<c64>::zeros(h.len(), h.len());
    for s in springs {
        let (f, k) = (s.frame, s.stiffness);
        let g = |a: usize, b: usize| (0..3).map(|l| f[l][a] * k[l] * f[l][b]).sum::<f64>();
        let mut l: Vec<(usize, [c64; 3])> = Vec::new();
        for &(node, coeff, target) in &s.terms {
            for d in 0..3usize {
                let row = h
                    .row_of(node, d as u8)
                    .expect("contact/target node is a ROM master");
                let col = if target {
                    // column d of R^σ: the components of r that u_t[d] moves
                    rot.map(|r| -e * coeff * r[d])
                } else {
                    std::array::from_fn(|a| c64::new(if a == d { coeff } else { 0.0 }, 0.0))
                };
                l.push((row, col));
            }
        }
        for &(ri, li) in &l {
            for &(rj, lj) in &l {
                let mut v = c64::new(0.0, 0.0);
                for (a, la) in li.iter().enumerate() {
                    for (b, lb) in lj.iter().enumerate() {
                        v += la.conj() * g(a, b) * lb;
                    }
                }
                kc[(ri, rj)] += v;
            }
        }
    }
    kc
}

/// Eigenfrequencies (Hz) below `max_hz` of (K + K_c, M) by M = L Lᴴ, L⁻¹ (K + K_c) L⁻ᴴ.
fn frequencies(h: &HarmonicRom, kc: &Mat<c64>, max_hz: f64) -> Result<Vec<f64>> {
    use faer::linalg::triangular_solve::solve_lower_triangular_in_place;
    let llt = h
        .mass
        .llt(faer::Side::Lower)
        .map_err(|e| nlrom::error::Error::Compute(format!("mass not positive definite: {e:?}")))?;
    let mut y = &h.stiffness + kc;
    solve_lower_triangular_in_place(llt.L(), y.as_mut(), faer::Par::Seq);
    let mut a = y.adjoint().to_owned();
    solve_lower_triangular_in_place(llt.L(), a.as_mut(), faer::Par::Seq);
    let a = Mat::from_fn(a.nrows(), a.ncols(), |i, j| {
        (a[(i, j)] + a[(j, i)].conj()) * 0.5
    });
    let (values, _) = self_adjoint_eigen_qr(a.as_ref())?;
    Ok(values
        .iter()
        .map(|&l| l.max(0.0).sqrt() / (2.0 * std::f64::consts::PI))
        .filter(|&f| f < max_hz)
        .collect())
}

fn main() -> Result<()> {
    let args: Vec<String> = std::env::args().collect();
    let Some(path) = args.get(1) else {
        eprintln!("usage: stuck_frequencies CASE.toml [KT_SCALE]");
        std::process::exit(2);
    };
    let scale: f64 = args.get(2).map_or(Ok(1.0), |s| s.parse()).unwrap_or(1.0);
    let mut case = Case::load(Path::new(path))?;
    let model = model::build(&case, &mut |_| {})?;
    let rom = reduce(&case, &model, &mut |_| {})?;
    let mesh = model.mesh.as_ref().expect("a mesh case");
    let geom = rom.cyclic.expect("a cyclic case");
    let m = case
        .excitation
        .as_ref()
        .and_then(|e| e.engine_order)
        .unwrap_or(0);
    let k = m % geom.sectors;
    let h = rom.harmonic(k).expect("the ROM holds k_1");
    case.contact[0].coupling = Some(SamaCoupling::Array);
    let array = build_interfaces(&case, mesh, Some(&geom))?.remove(0);
    case.contact[0].coupling = Some(SamaCoupling::Interpolated);
    let shape = build_interfaces(&case, mesh, Some(&geom))?.remove(0);
    let e = c64::from_polar(1.0, array.sigma as f64 * phase(k, geom.sectors));
    let rot = geom.rotation(array.sigma);
    let max_hz = 1500.0;
    println!("{path}: k = {k}, k_t scale {scale}");
    let zero = Mat::<c64>::zeros(h.len(), h.len());
    println!("free               {:.2?}", frequencies(h, &zero, max_hz)?);
    for (label, iface, parallel) in [
        ("array             ", &array, true),
        ("idw-interpolated  ", &array, false),
        ("shape-interpolated", &shape, false),
    ] {
        let kc = assemble(h, &springs(iface, parallel, scale), e, rot);
        println!("{label} {:.2?}", frequencies(h, &kc, max_hz)?);
    }
    Ok(())
}
