//! Fully stuck natural frequencies of a shroud case for the SAMA couplings, and with `--shapes`
//! what each stuck mode does on the blade (how M1 and M2 of docs/validation.md were chosen).
//!
//!     cargo run --release --example stuck_frequencies -- CASE.toml [KT_SCALE] [MAX_HZ] [--shapes]
//!
//! The ROM of the excitation's harmonic index k_1 plus linear springs (k_t, k_t, k_n per contact
//! node, times KT_SCALE, default 1) on the contact pairs of the case's first `[[contact]]`,
//! assembled here independently of the harmonic balance: r = u_c − e^{iσφ_k} R_α^σ Σ_j w_j u_tj.
//! Printed: the generalized eigenfrequencies (Hz) below MAX_HZ (default 1500) of (K + K_c, M) for
//! - `free`: no contact;
//! - `array`: SAMA's parallel pairs c–t_j with k_tj = w_j k_t (eq 31; node-to-node when w = 1);
//! - `idw-interpolated`: one spring per node on u_c − Σ_j w_j u_tj with the inverse-distance w_j;
//! - `shape-interpolated`: one spring per node on u_c − Σ_j N_j u_tj (`coupling = "interpolated"`).
//!
//! `--shapes` adds four probe nodes to the ROM masters (so the frequencies are those of a slightly
//! richer Craig–Bampton basis): the blade's leading edge (LE, least axial coordinate) and trailing
//! edge (TE, largest) at the excitation node's radius (mid span) and at 90 % of the way from there
//! to the shroud (tip). For each stuck mode of the case's own coupling (mass-normalised φ, phase
//! set so that the largest probe component is real) it prints, per span, with n the blade-plate
//! normal (chord × radial) and c the chord direction (LE → TE):
//! - `flap` = n·(u_LE + u_TE)/2: out-of-plane translation (bending about the chord);
//! - `edge` = c·(u_LE + u_TE)/2: in-plane chordwise translation (edgewise bending);
//! - `tors` = n·(u_TE − u_LE)/2: opposite out-of-plane motion of the edges, i.e. a rotation
//!   about the radial axis (torsion) of angle 2·tors/|chord|;
//!
//! all in m for φᴴMφ = 1, and `u_exc` = the axial component of φ at the excitation node, whose
//! square over 2ζω² is the linear peak amplitude per newton of axial force (modal damping ζ).
use std::path::Path;

use faer::{c64, Mat};
use nlrom::case::{Case, Excitation, ExcitationLoad, SamaCoupling};
use nlrom::cyclic::{phase, CyclicGeometry};
use nlrom::eigen::self_adjoint_eigen_qr;
use nlrom::error::Result;
use nlrom::interface::{build_interfaces, ContactInterface};
use nlrom::mesh::{ElementBlock, ElementType, Mesh, PhysicalGroup};
use nlrom::model;
use nlrom::reduction::reduce;
use nlrom::rom::HarmonicRom;

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

/// Stuck modes below `max_hz` of (K + K_c, M): frequencies (Hz) and the M-normalised vectors
/// (columns), by M = L Lᴴ, A = L⁻¹ (K + K_c) L⁻ᴴ = Y Λ Yᴴ, Φ = L⁻ᴴ Y.
fn modes(h: &HarmonicRom, kc: &Mat<c64>, max_hz: f64) -> Result<(Vec<f64>, Mat<c64>)> {
    use faer::linalg::triangular_solve::{
        solve_lower_triangular_in_place, solve_upper_triangular_in_place,
    };
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
    let (values, mut vectors) = self_adjoint_eigen_qr(a.as_ref())?;
    solve_upper_triangular_in_place(llt.L().adjoint(), vectors.as_mut(), faer::Par::Seq);
    let hz: Vec<f64> = values
        .iter()
        .map(|&l| l.max(0.0).sqrt() / (2.0 * std::f64::consts::PI))
        .take_while(|&f| f < max_hz)
        .collect();
    let phi = vectors.subcols(0, hz.len()).to_owned();
    Ok((hz, phi))
}

type Vec3 = [f64; 3];

fn sub(a: Vec3, b: Vec3) -> Vec3 {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

fn dot(a: Vec3, b: Vec3) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

fn unit(a: Vec3) -> Vec3 {
    let n = dot(a, a).sqrt();
    a.map(|x| x / n)
}

fn cross(a: Vec3, b: Vec3) -> Vec3 {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

/// Unit radial direction at `x` (away from the cyclic axis).
fn radial_unit(geom: &CyclicGeometry, x: Vec3) -> Vec3 {
    let v = sub(x, geom.origin);
    let a = dot(v, geom.axis);
    unit(std::array::from_fn(|d| v[d] - a * geom.axis[d]))
}

/// Leading- and trailing-edge nodes of the blade at one radius (Gmsh tags and positions).
struct Span {
    label: &'static str,
    le: (u64, Vec3),
    te: (u64, Vec3),
}

/// Radial component r(x) and axial coordinate z(x) about the cyclic axis.
fn cylindrical(geom: &CyclicGeometry, x: Vec3) -> (f64, f64) {
    (
        geom.distance_to_axis(x),
        dot(sub(x, geom.origin), geom.axis),
    )
}

/// The blade's edge nodes at radius ≈ `r`: among the nodes within 2 mm of r and inside
/// `r_max`, the least (LE) and largest (TE) axial coordinate.
fn span_at(mesh: &Mesh, geom: &CyclicGeometry, label: &'static str, r: f64, r_max: f64) -> Span {
    let band = mesh.coords.iter().enumerate().filter(|(_, &x)| {
        let (rx, _) = cylindrical(geom, x);
        (rx - r).abs() < 2e-3 && rx < r_max - 1e-9
    });
    let z = |x: &Vec3| cylindrical(geom, *x).1;
    let (lo, hi) = band.fold((None::<usize>, None::<usize>), |(lo, hi), (i, x)| {
        let better = |j: Option<usize>, less: bool| match j {
            Some(j) if (z(x) < z(&mesh.coords[j])) != less => Some(j),
            _ => Some(i),
        };
        (better(lo, true), better(hi, false))
    });
    let node = |i: usize| (mesh.node_tags[i], mesh.coords[i]);
    Span {
        label,
        le: node(lo.expect("blade nodes at the probe radius")),
        te: node(hi.expect("blade nodes at the probe radius")),
    }
}

/// The probe spans (mid = excitation radius, tip = 90 % of the way to the shroud) and a point
/// group `probe` holding their nodes, added to the mesh so that the ROM keeps them as masters.
fn add_probes(
    mesh: &mut Mesh,
    geom: &CyclicGeometry,
    exc: &str,
    shroud: &str,
) -> Result<Vec<Span>> {
    let r_of = |n: u32| geom.distance_to_axis(mesh.coords[n as usize]);
    let r_mid = r_of(mesh.nodes_of(exc)?[0]);
    let r_shroud = mesh
        .nodes_of(shroud)?
        .into_iter()
        .map(r_of)
        .fold(f64::MAX, f64::min);
    let r_tip = r_mid + 0.9 * (r_shroud - r_mid);
    let spans = vec![
        span_at(mesh, geom, "mid", r_mid, r_shroud),
        span_at(mesh, geom, "tip", r_tip, r_shroud),
    ];
    let tag = mesh.groups.iter().map(|g| g.tag).max().unwrap_or(0) + 1;
    mesh.groups.push(PhysicalGroup {
        name: "probe".into(),
        dim: 0,
        tag,
    });
    let nodes: Vec<u64> = spans.iter().flat_map(|s| [s.le.0, s.te.0]).collect();
    mesh.blocks.push(ElementBlock {
        kind: ElementType::Point,
        entity: 0,
        physicals: vec![tag],
        tags: (0..nodes.len() as u64).map(|e| u64::MAX - e).collect(),
        connectivity: nodes.iter().filter_map(|&t| mesh.node_index(t)).collect(),
    });
    Ok(spans)
}

/// Displacement (complex, global frame) of mode column `phi` at node `tag`.
fn at(h: &HarmonicRom, phi: faer::ColRef<'_, c64>, tag: u64) -> [c64; 3] {
    std::array::from_fn(|d| phi[h.row_of(tag, d as u8).expect("probe node is a master")])
}

/// One line per mode: frequency, `flap`/`edge`/`tors` per span and `u_exc` (module docs).
fn print_shapes(
    h: &HarmonicRom,
    hz: &[f64],
    phi: &Mat<c64>,
    spans: &[Span],
    geom: &CyclicGeometry,
    exc: u64,
) {
    println!(
        "  mode      f (Hz)  span        flap        edge        tors   twist/flap  u_exc (axial)"
    );
    for (j, f) in hz.iter().enumerate() {
        let col = phi.col(j);
        // phase: the largest probe component real and positive
        let all: Vec<c64> = spans
            .iter()
            .flat_map(|s| [at(h, col, s.le.0), at(h, col, s.te.0)])
            .flatten()
            .collect();
        let big = all.iter().fold(
            c64::new(0.0, 0.0),
            |m, &v| if v.norm() > m.norm() { v } else { m },
        );
        let turn = big.conj() / big.norm();
        let re = |u: [c64; 3]| u.map(|v| (v * turn).re);
        let u_exc = (0..3)
            .map(|d| re(at(h, col, exc))[d] * geom.axis[d])
            .sum::<f64>();
        for (i, s) in spans.iter().enumerate() {
            let (ul, ut) = (re(at(h, col, s.le.0)), re(at(h, col, s.te.0)));
            let chord = sub(s.te.1, s.le.1);
            let radial = radial_unit(geom, std::array::from_fn(|d| 0.5 * (s.le.1[d] + s.te.1[d])));
            let n = unit(cross(chord, radial));
            let c = unit(chord);
            let mean: Vec3 = std::array::from_fn(|d| 0.5 * (ul[d] + ut[d]));
            let half: Vec3 = std::array::from_fn(|d| 0.5 * (ut[d] - ul[d]));
            let (flap, edge, tors) = (dot(n, mean), dot(c, mean), dot(n, half));
            let head = if i == 0 {
                format!("{:>6} {:>11.2}", j + 1, f)
            } else {
                " ".repeat(18)
            };
            let tail = if i == 0 {
                format!("  {u_exc:+.3e}")
            } else {
                String::new()
            };
            println!(
                "{head}  {:<4} {flap:+.3e} {edge:+.3e} {tors:+.3e} {:>+11.2}{tail}",
                s.label,
                tors / flap
            );
        }
    }
}
fn main() -> Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let shapes = args.iter().any(|a| a == "--shapes");
    let pos: Vec<&String> = args.iter().filter(|a| !a.starts_with("--")).collect();
    let Some(path) = pos.first() else {
        eprintln!("usage: stuck_frequencies CASE.toml [KT_SCALE] [MAX_HZ] [--shapes]");
        std::process::exit(2);
    };
    let number =
        |i: usize, default: f64| pos.get(i).map_or(default, |s| s.parse().unwrap_or(default));
    let (scale, max_hz) = (number(1, 1.0), number(2, 1500.0));
    let mut case = Case::load(Path::new(path.as_str()))?;
    let mut model = model::build(&case, &mut |_| {})?;
    let cyclic = case.cyclic.as_ref().expect("a cyclic case");
    let geom = CyclicGeometry::from_case(cyclic)?;
    let exc_group = match &case.excitation {
        Some(Excitation {
            load: ExcitationLoad::Group { group, .. },
            ..
        }) => group.clone(),
        _ => {
            return Err(nlrom::error::Error::input(format!(
                "{path}: stuck_frequencies needs `[excitation] group` (the probe radius)"
            )))
        }
    };
    let spans = if shapes {
        let mesh = model.mesh.as_mut().expect("a mesh case");
        let spans = add_probes(mesh, &geom, &exc_group, &case.contact[0].contact)?;
        if let Some(r) = case.reduction.as_mut() {
            r.keep.push("probe".into());
        }
        spans
    } else {
        Vec::new()
    };
    let rom = reduce(&case, &model, &mut |_| {})?;
    let mesh = model.mesh.as_ref().expect("a mesh case");
    let exc_tag = mesh.node_tags[mesh.nodes_of(&exc_group)?[0] as usize];
    let geom = rom.cyclic.expect("a cyclic case");
    let m = case
        .excitation
        .as_ref()
        .and_then(|e| e.engine_order)
        .unwrap_or(0);
    let k = m % geom.sectors;
    let h = rom.harmonic(k).expect("the ROM holds k_1");
    let own = case.contact[0].coupling.unwrap_or_default();
    case.contact[0].coupling = Some(SamaCoupling::Array);
    let array = build_interfaces(&case, mesh, Some(&geom))?.remove(0);
    case.contact[0].coupling = Some(SamaCoupling::Interpolated);
    let shape = build_interfaces(&case, mesh, Some(&geom))?.remove(0);
    let e = c64::from_polar(1.0, array.sigma as f64 * phase(k, geom.sectors));
    let rot = geom.rotation(array.sigma);
    println!("{path}: k = {k}, k_t scale {scale}, below {max_hz} Hz");
    let zero = Mat::<c64>::zeros(h.len(), h.len());
    let (hz, phi) = modes(h, &zero, max_hz)?;
    println!("free               {hz:.2?}");
    if shapes {
        for s in &spans {
            println!(
                "  {} span: LE node {} at {:.4?}, TE node {} at {:.4?}",
                s.label, s.le.0, s.le.1, s.te.0, s.te.1
            );
        }
        print_shapes(h, &hz, &phi, &spans, &geom, exc_tag);
    }
    for (label, iface, parallel) in [
        ("array             ", &array, true),
        ("idw-interpolated  ", &array, false),
        ("shape-interpolated", &shape, false),
    ] {
        let kc = assemble(h, &springs(iface, parallel, scale), e, rot);
        let (hz, phi) = modes(h, &kc, max_hz)?;
        println!("{label} {hz:.2?}");
        let mine = matches!(
            (own, parallel, label.trim()),
            (SamaCoupling::Array, true, _)
                | (SamaCoupling::Interpolated, false, "shape-interpolated")
        );
        if shapes && mine {
            print_shapes(h, &hz, &phi, &spans, &geom, exc_tag);
        }
    }
    Ok(())
}
