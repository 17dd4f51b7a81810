//! The bar damper's bar (Cigeroglu, An & Menq 2007, §4.1, as a solid: clamped at x = 0, pads on
//! z = 0 and z = a) for the face-strip tests and tools (`tests/strip_face.rs`,
//! `tests/strip_face_rom.rs`, `tools/validation/strip_face_rom.rs`): a structured mesh of
//! first-order hexahedra of chosen size written as a Gmsh MSH 2.2 ASCII file, the case text with
//! one strip, and the agreement of two solutions' tip harmonics and strip maps.
//!
//! The mesh: the bar [0, L] × [0, b] × [0, a] with nx × ny × nz elements; groups `volume` (3),
//! `clamp` (2, the faces at x = 0), `tip` (2, x = L) and `pads` (2, the faces z = 0 and z = a),
//! as `meshes/damper_bar.msh` with a finer cross-section when nz > 1, so that the nodes inside
//! the bar are not on a pad.
#![allow(dead_code)]

use std::f64::consts::TAU;
use std::fmt::Write as _;
use std::path::Path;

use nlrom::case::Case;
use nlrom::commands::progress::Reporter;
use nlrom::commands::solve::{solve_case, SolveOptions};
use nlrom::output::{ContactMap, ResultsFile};
use nlrom::problem::rom_store::RomPolicy;

/// The bar's dimensions (m) and element counts.
#[derive(Clone, Copy, Debug)]
pub struct HexBar {
    pub length: f64,
    pub width: f64,
    pub height: f64,
    pub nx: usize,
    pub ny: usize,
    pub nz: usize,
}

impl HexBar {
    /// Number of nodes.
    pub fn nodes(&self) -> usize {
        (self.nx + 1) * (self.ny + 1) * (self.nz + 1)
    }

    /// Gmsh tag of the node (i, j, k).
    fn node(&self, i: usize, j: usize, k: usize) -> usize {
        1 + i + (self.nx + 1) * (j + (self.ny + 1) * k)
    }

    /// Writes the mesh to `path`.
    pub fn write(&self, path: &Path) -> std::io::Result<()> {
        let mut s = String::new();
        s.push_str("$MeshFormat\n2.2 0 8\n$EndMeshFormat\n");
        s.push_str("$PhysicalNames\n4\n3 1 \"volume\"\n2 2 \"clamp\"\n2 3 \"tip\"\n2 4 \"pads\"\n$EndPhysicalNames\n");
        let _ = writeln!(s, "$Nodes\n{}", self.nodes());
        for k in 0..=self.nz {
            for j in 0..=self.ny {
                for i in 0..=self.nx {
                    let x = self.length * i as f64 / self.nx as f64;
                    let y = self.width * j as f64 / self.ny as f64;
                    let z = self.height * k as f64 / self.nz as f64;
                    let _ = writeln!(s, "{} {x:e} {y:e} {z:e}", self.node(i, j, k));
                }
            }
        }
        s.push_str("$EndNodes\n");
        let mut elements: Vec<String> = Vec::new();
        let (nx, ny, nz) = (self.nx, self.ny, self.nz);
        for k in 0..nz {
            for j in 0..ny {
                for i in 0..nx {
                    let n = |a: usize, b: usize, c: usize| self.node(i + a, j + b, k + c);
                    elements.push(format!(
                        "5 2 1 1 {} {} {} {} {} {} {} {}",
                        n(0, 0, 0),
                        n(1, 0, 0),
                        n(1, 1, 0),
                        n(0, 1, 0),
                        n(0, 0, 1),
                        n(1, 0, 1),
                        n(1, 1, 1),
                        n(0, 1, 1)
                    ));
                }
            }
        }
        for (i, group) in [(0, 2), (nx, 3)] {
            for k in 0..nz {
                for j in 0..ny {
                    elements.push(format!(
                        "3 2 {group} {group} {} {} {} {}",
                        self.node(i, j, k),
                        self.node(i, j + 1, k),
                        self.node(i, j + 1, k + 1),
                        self.node(i, j, k + 1)
                    ));
                }
            }
        }
        for k in [0, nz] {
            for j in 0..ny {
                for i in 0..nx {
                    elements.push(format!(
                        "3 2 4 4 {} {} {} {}",
                        self.node(i, j, k),
                        self.node(i + 1, j, k),
                        self.node(i + 1, j + 1, k),
                        self.node(i, j + 1, k)
                    ));
                }
            }
        }
        let _ = writeln!(s, "$Elements\n{}", elements.len());
        for (e, line) in elements.iter().enumerate() {
            let _ = writeln!(s, "{} {line}", e + 1);
        }
        s.push_str("$EndElements\n");
        std::fs::write(path, s)
    }
}

/// The bar case on `mesh` (E = 200 GPa, ν = 0.3, ρ = 7800 kg/m³, 0.5 % modal damping, 2 N
/// axial at the tip, the tip's response) with one strip `pads` given by the TOML lines `strip`,
/// then the tables `extra`.
pub fn case_text(mesh: &Path, strip: &str, extra: &str) -> String {
    format!(
        r#"
[model]
mesh = "{mesh}"
material = {{ young = 200e9, poisson = 0.3, density = 7800.0 }}
clamp = ["clamp"]
damping = {{ modal = 0.005 }}

[excitation]
group = "tip"
force = [2.0, 0.0, 0.0]

[response]
groups = ["tip"]

[[strip]]
name = "pads"
{strip}
{extra}
"#,
        mesh = mesh.display()
    )
}

/// The results of `nlrom solve` on `case` (silent).
pub fn solve(case: &Case) -> ResultsFile {
    solve_case(
        case,
        &SolveOptions::new(RomPolicy::ReadIfMatching),
        &Reporter::silent(),
    )
    .unwrap()
    .results
}

/// How two solutions of the same strip case agree at their maps (one per map frequency, in the
/// same order).
#[derive(Clone, Copy, Debug, Default)]
pub struct Agreement {
    /// Largest difference of the first curve's tip harmonics at a map's point, over their
    /// amplitude.
    pub harmonics: f64,
    /// Largest difference of a transition angle (rad).
    pub angle: f64,
    /// Map samples in another state away from a transition (farther than `near` rad).
    pub differ: usize,
    /// Whether a map has both stick and slip.
    pub mixed: bool,
}

/// The tip amplitude of `b` at map `mb`'s point (the largest of its response harmonics) and the
/// largest difference of `a`'s harmonics at map `ma`'s point from them.
pub fn harmonics_difference(
    a: &ResultsFile,
    b: &ResultsFile,
    ma: &ContactMap,
    mb: &ContactMap,
) -> (f64, f64) {
    assert_eq!(ma.omega, mb.omega);
    let ha = &a.frfs[0].points[ma.point].harmonics;
    let hb = &b.frfs[0].points[mb.point].harmonics;
    assert_eq!(ha.len(), hb.len());
    let amp = hb.iter().map(|h| h.norm()).fold(0.0, f64::max);
    let off = ha
        .iter()
        .zip(hb)
        .map(|(x, y)| (x - y).norm())
        .fold(0.0, f64::max);
    (amp, off)
}

/// The largest difference of the response harmonics of `a` and `b` at their maps' points (the
/// same frequencies, in the same order) relative to the tip amplitude there, without comparing
/// the maps (which may differ in their transitions, e.g. on a truncated modal basis).
pub fn response_difference(a: &ResultsFile, b: &ResultsFile) -> f64 {
    assert_eq!(a.maps.len(), b.maps.len());
    a.maps
        .iter()
        .zip(&b.maps)
        .map(|(ma, mb)| {
            let (amp, off) = harmonics_difference(a, b, ma, mb);
            off / amp
        })
        .fold(0.0, f64::max)
}

/// The agreement of `a` and `b` at their maps, where each strip point e of `b` stands for the
/// points `per`·e .. `per`·(e + 1) of `a`; prints one line per map.
pub fn agreement(a: &ResultsFile, b: &ResultsFile, per: usize, near: f64) -> Agreement {
    assert_eq!(a.maps.len(), b.maps.len());
    let apart = |x: f64, y: f64| {
        let d = (x - y).rem_euclid(TAU);
        d.min(TAU - d)
    };
    let mut out = Agreement::default();
    for (ma, mb) in a.maps.iter().zip(&b.maps) {
        let (amp, off) = harmonics_difference(a, b, ma, mb);
        let n = ma.phase.len();
        assert_eq!(ma.position.len(), per * mb.position.len());
        let (mut differ, mut angle) = (0usize, 0.0f64);
        for e in 0..mb.position.len() {
            let tb = &mb.transition_angles
                [mb.transition_offsets[e] as usize..mb.transition_offsets[e + 1] as usize];
            for f in per * e..per * (e + 1) {
                let ta = &ma.transition_angles
                    [ma.transition_offsets[f] as usize..ma.transition_offsets[f + 1] as usize];
                assert_eq!(ta.len(), tb.len(), "transitions of point {f}");
                for (x, y) in ta.iter().zip(tb) {
                    angle = angle.max(apart(*x, *y));
                }
                for j in 0..n {
                    let close = ta.iter().chain(tb).any(|&t| apart(t, ma.phase[j]) < near);
                    if !close && ma.state[f * n + j] != mb.state[e * n + j] {
                        differ += 1;
                    }
                }
            }
        }
        let count = |code: i64| mb.state.iter().filter(|&&s| s == code).count();
        eprintln!(
            "{:.1} Hz: tip amplitude {amp:.4e} m, difference {:.2e} of it; maps: {differ} samples differ, angles within {angle:.2e} rad; samples stick {} slip {}",
            ma.omega / TAU,
            off / amp,
            count(0),
            count(-1) + count(1)
        );
        out.harmonics = out.harmonics.max(off / amp);
        out.angle = out.angle.max(angle);
        out.differ += differ;
        out.mixed |= count(0) > 0 && count(-1) + count(1) > 0;
    }
    out
}
