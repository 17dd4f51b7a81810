//! The reduced model of a sector as a march: the real ROM of a mesh case (`[reduction]`, optional
//! `[cyclic]`) with its `[[contact]]` interfaces as friction elements of [`crate::march::element`].
//!
//! The pieces are those of the harmonic balance ([`super::sector::SectorProblem`]): the ROM of
//! [`super::rom_store`] (read from `[rom] file` when its key matches, else reduced),
//! the contact pairs of [`crate::interface::build_interfaces`] on the ROM's physical master rows, the
//! excitation and response groups. A time-domain model of the reference sector is real when its
//! ROM is (`docs/conventions.md` §2):
//! - no `[cyclic]`: the Craig–Bampton structure, frontiers as they are;
//! - harmonic index k = 0 (engine order m ≡ 0 mod N, all sectors in phase): the target of a pair
//!   with σ ≠ 0 moves as R_α^σ u_t;
//! - k = N/2 (N even, m ≡ N/2 mod N): neighbours in antiphase, the target moves as −R_α^σ u_t. The
//!   march imposes this on the whole response, whereas the harmonic balance puts the static part
//!   and the even temporal harmonics on k = 0 (k_n = n·m mod N): the two agree while the response
//!   has no even harmonics (e.g. a stuck or symmetric contact), and differ by the even harmonics
//!   otherwise.
//!
//! A travelling wave (k ≠ 0, N/2) has a complex ROM; its march is that of the sectors of one wave
//! period ([`super::travelling_wave`]), reported on the reference sector.
//!
//! Contact (SAMA paper, Battiato 2021, §3 and eq. 33; `docs/theory.md`): each node-to-node pair
//! (u1, u2, v) = P (u_c − e^{iσφ_k} R_α^σ u_t), P = [t1; t2; −n], becomes two 1-D elements of the
//! time-discrete law of [`crate::contact::law`] (t1 and t2, each with its own slider and the limit
//! μ f_n of the pair's normal force, which the first applies). The forces are measured from the
//! preloaded static equilibrium as in the harmonic balance ([`crate::hbm::preload`]):
//! f̃_c(q) = f_c(q) − f_c(0), i.e. the constant −f_c(0) joins the external force, q = 0 is the
//! static equilibrium and the march starts there at rest.

use super::rom_store::{sector_rom, RomPolicy};
use super::sector::SectorDofs;
use super::travelling_wave::travelling_wave;
use super::Log;
use crate::case::{Case, ContactElement};
use crate::contact::pairs::PairElement;
use crate::error::{Error, Result};
use crate::interface::{build_interfaces, ContactInterface};
use crate::march::element::{Direction, Element};
use crate::march::schemes::{add_contact_force, evaluate_law};
use crate::march::signal::Harmonic;
use crate::march::{InitialCondition, MarchSystem};
use crate::output::ResponseDof;
use crate::rom::{HarmonicRom, ReducedDof, Rom};

/// The marched sector model, its reported rows and their node labels.
pub struct SectorMarch {
    /// The model: the real ROM coordinates of one harmonic index, or the sectors of one period
    /// of a travelling wave.
    pub system: MarchSystem,
    /// Reported rows (output DOFs: `[response]` groups, else the excitation group, × x y z).
    pub response: Vec<usize>,
    /// The reported rows as node DOFs.
    pub response_dofs: Vec<ResponseDof>,
    /// The harmonic index k of the marched ROM.
    pub harmonic_index: usize,
}

/// Builds the march of the sector case `case` (module documentation). `log` receives progress.
///
/// Errors ([`Error::Input`]): the 2-D friction element, a missing
/// or matrix-row excitation, nodes that are not physical ROM coordinates, and the errors of the
/// reduction and of the contact interfaces.
pub fn sector_march(case: &Case, log: &mut dyn FnMut(&str)) -> Result<SectorMarch> {
    let (k, wave) = harmonic_index(case)?;
    check_friction_elements(case)?;
    if let Some(m) = wave {
        return travelling_march(case, k, m, log);
    }
    let (rom, mesh, _) = sector_rom(case, &RomPolicy::ReadIfMatching, &StageLog::new(log))?;
    let h = rom.harmonic(k).ok_or_else(|| {
        Error::input(format!(
            "{}: the ROM has no harmonic index k = {k}; rebuild it with `nlrom reduce`",
            case.path.display()
        ))
    })?;
    let phase = neighbour_phase(&rom, k);
    let interfaces = build_interfaces(case, &mesh, rom.cyclic.as_ref())?;
    let elements = contact_elements(h, &interfaces, phase)?;
    let dofs = SectorDofs::new(case, &mesh)?;
    let force = excitation(&dofs, h)?;
    let response = dofs.output_rows(h)?;
    let system = march_system(
        h.len(),
        [
            real_dense(&h.mass, "mass")?,
            match &h.damping {
                Some(c) => real_dense(c, "damping")?,
                None => vec![0.0; h.len() * h.len()],
            },
            real_dense(&h.stiffness, "stiffness")?,
        ],
        force,
        elements,
        h.dofs.iter().map(dof_name).collect(),
        &case.path.display().to_string(),
    )?;
    log(&format!(
        "sector ROM of harmonic index k = {k}: {} coordinates, {} friction elements on {} contact pairs{}",
        system.n,
        system.elements.len(),
        system.elements.len() / 2,
        match phase {
            Some(p) if p < 0.0 => ", neighbours in antiphase",
            Some(_) => ", neighbours in phase",
            None => "",
        }
    ));
    Ok(SectorMarch {
        system,
        response,
        response_dofs: response_dofs(&dofs),
        harmonic_index: k,
    })
}

/// The march of a travelling wave of engine order `m` (harmonic index `k`): the sectors of one
/// wave period of [`super::travelling_wave`], on a ROM holding every harmonic index
/// n·m mod N (n = 0..N − 1) the wave can excite.
fn travelling_march(
    case: &Case,
    k: usize,
    m: usize,
    log: &mut dyn FnMut(&str),
) -> Result<SectorMarch> {
    let mut all = case.clone();
    let n_sec = case.cyclic.as_ref().map_or(1, |g| g.sectors);
    all.harmonic_balance.harmonics = all.harmonic_balance.harmonics.max(n_sec - 1);
    let (rom, mesh, _) = sector_rom(&all, &RomPolicy::ReadIfMatching, &StageLog::new(log))?;
    let interfaces = build_interfaces(case, &mesh, rom.cyclic.as_ref())?;
    let dofs = SectorDofs::new(case, &mesh)?;
    let what = case.path.display().to_string();
    let wave = travelling_wave(&rom, m, &interfaces, &dofs, &what)?;
    let system = march_system(
        wave.n,
        [wave.mass, wave.damping, wave.stiffness],
        wave.force,
        wave.elements,
        wave.dof_names,
        &what,
    )?;
    log(&format!(
        "travelling wave of harmonic index k = {k} (engine order {m}): {} sectors of one wave period on the ROMs of k = {:?}, {} coordinates, {} friction elements on {} contact pairs",
        wave.sectors,
        wave.blocks,
        system.n,
        system.elements.len(),
        system.elements.len() / 2,
    ));
    Ok(SectorMarch {
        system,
        response: wave.response,
        response_dofs: response_dofs(&dofs),
        harmonic_index: k,
    })
}

/// The output DOFs of `dofs` as results-file response DOFs.
fn response_dofs(dofs: &SectorDofs) -> Vec<ResponseDof> {
    dofs.outputs
        .iter()
        .map(|d| ResponseDof::Node {
            tag: d.node_tag,
            component: d.component,
        })
        .collect()
}

/// The march system with the real matrices `[mass, damping, stiffness]` (row-major n × n), the
/// external `force`, the contact `elements` and a name per coordinate, its contact force
/// measured from the static equilibrium, starting at rest; `what` names the case in messages.
fn march_system(
    n: usize,
    [mass, damping, stiffness]: [Vec<f64>; 3],
    force: Vec<Harmonic>,
    elements: Vec<Element>,
    dof_names: Vec<String>,
    what: &str,
) -> Result<MarchSystem> {
    let mut system = MarchSystem {
        n,
        mass,
        damping,
        stiffness,
        force,
        damping_force: Vec::new(),
        elements,
        dof_names,
        initial: InitialCondition::Rest,
        displacement_scale: 1.0,
    };
    subtract_force_at_rest(&mut system);
    system.displacement_scale = system.default_displacement_scale();
    system.validate(what)?;
    Ok(system)
}

/// The harmonic index k of the march: 0 without cyclic symmetry, else m mod N of the
/// excitation's engine order m; with the engine order m when k is a travelling wave
/// (k ≠ 0, N/2).
fn harmonic_index(case: &Case) -> Result<(usize, Option<usize>)> {
    let Some(g) = &case.cyclic else {
        return Ok((0, None));
    };
    let n = g.sectors;
    let m = case
        .excitation
        .as_ref()
        .and_then(|e| e.engine_order)
        .ok_or_else(|| {
            Error::input(format!(
                "{}: [excitation] needs `engine_order` for a cyclic model",
                case.path.display()
            ))
        })?;
    let k = m % n;
    Ok((k, (k != 0 && 2 * k != n).then_some(m)))
}

/// Every `[[contact]]` must use the 1-D friction element (the march's elements have one
/// tangential direction each; the 2-D Coulomb disc couples two).
fn check_friction_elements(case: &Case) -> Result<()> {
    match case.contact.iter().find(|c| c.element != ContactElement::OneD) {
        Some(c) => Err(Error::input(format!(
            "{}: [[contact]] '{}' has element = \"2d\" (Coulomb disc); `nlrom march` integrates the 1-D law (t1 and t2 independent, each with its own slider): set `element = \"1d\"`",
            case.path.display(),
            c.name
        ))),
        None => Ok(()),
    }
}

/// e^{iσφ_k} for σ = 1 (real: +1 for k = 0, −1 for k = N/2); `None` without cyclic symmetry.
fn neighbour_phase(rom: &Rom, k: usize) -> Option<f64> {
    rom.cyclic.as_ref().map(|_| if k == 0 { 1.0 } else { -1.0 })
}

/// The real part of a ROM matrix, row-major; errors if it is not real.
fn real_dense(a: &faer::Mat<faer::c64>, name: &str) -> Result<Vec<f64>> {
    let n = a.nrows();
    let mut out = Vec::with_capacity(n * n);
    for i in 0..n {
        for j in 0..n {
            let v = a[(i, j)];
            if v.im != 0.0 {
                return Err(Error::Compute(format!(
                    "the ROM's {name} matrix has an imaginary entry ({i}, {j}) = {:e}: not a real model",
                    v.im
                )));
            }
            out.push(v.re);
        }
    }
    Ok(out)
}

/// A name per ROM coordinate: `node 12 x`, `interface 3`, `mode 5`.
fn dof_name(d: &ReducedDof) -> String {
    match d {
        ReducedDof::Physical {
            node_tag,
            component,
            ..
        } => format!(
            "node {node_tag} {}",
            ["x", "y", "z"][*component as usize % 3]
        ),
        ReducedDof::Interface { index } => format!("interface {index}"),
        ReducedDof::Modal { mode } => format!("mode {mode}"),
    }
}

/// The friction elements of every pair of the interfaces on the ROM rows of `h` (two per pair).
fn contact_elements(
    h: &HarmonicRom,
    interfaces: &[ContactInterface],
    phase: Option<f64>,
) -> Result<Vec<Element>> {
    let mut out = Vec::new();
    for iface in interfaces {
        let rows = |tag: u64| -> Option<[usize; 3]> {
            Some([h.row_of(tag, 0)?, h.row_of(tag, 1)?, h.row_of(tag, 2)?])
        };
        for pair in iface.elements(rows)? {
            let c = if pair.sigma == 0 {
                1.0
            } else {
                phase.unwrap_or(1.0)
            };
            let tag = |row: usize| match h.dofs[row] {
                ReducedDof::Physical { node_tag, .. } => node_tag,
                _ => 0,
            };
            let label = match pair.target {
                Some(t) => format!("{} {}-{}", iface.name, tag(pair.contact[0]), tag(t[0])),
                None => format!("{} {}", iface.name, tag(pair.contact[0])),
            };
            out.extend(pair_elements(&pair, &iface.rotation, c, &label));
        }
    }
    Ok(out)
}

/// The two 1-D elements (t1, t2) of a pair: local a = P_a·u_c − c (P R^σ)_a·u_t with
/// P = [t1; t2; −n], R^σ the target's rotation and c the neighbour phase.
/// `label` names the pair in messages and results.
pub(super) fn pair_elements(
    pair: &PairElement,
    rotation: &[[f64; 3]; 3],
    c: f64,
    label: &str,
) -> [Element; 2] {
    let f = pair.frame;
    let p = [f[0], f[1], [-f[2][0], -f[2][1], -f[2][2]]];
    let direction = |a: usize| -> Direction {
        let mut weights: Vec<(usize, f64)> = Vec::with_capacity(6);
        let mut add = |row: usize, w: f64| match weights.iter_mut().find(|(r, _)| *r == row) {
            Some(e) => e.1 += w,
            None => weights.push((row, w)),
        };
        for (&row, &w) in pair.contact.iter().zip(&p[a]) {
            add(row, w);
        }
        if let Some(t) = pair.target {
            for (j, &row) in t.iter().enumerate() {
                let pr: f64 = (0..3).map(|i| p[a][i] * rotation[i][j]).sum();
                add(row, -c * pr);
            }
        }
        weights.retain(|&(_, w)| w != 0.0);
        Direction {
            weights,
            prescribed: Harmonic::default(),
        }
    };
    let element = |a: usize| Element {
        name: format!("{label} t{}", a + 1),
        tangential: direction(a),
        normal: Some(direction(2)),
        params: pair.params,
        applies_normal: a == 0,
    };
    [element(0), element(1)]
}

/// The excitation of engine order m on the ROM coordinates: f = Re(F e^{iωt}) with F = T_kᴴ f
/// ([`SectorDofs::excitation_vector`]).
fn excitation(dofs: &SectorDofs, h: &HarmonicRom) -> Result<Vec<Harmonic>> {
    Ok(dofs
        .excitation_vector(h)?
        .iter()
        .map(|z| Harmonic {
            mean: 0.0,
            cos: z.re,
            sin: -z.im,
        })
        .collect())
}

/// Adds −f_c(0) (the contact force at rest, sliders at zero) to the static part of the external
/// force: the march then integrates f_c(q) − f_c(0), the contact force about the preloaded static
/// equilibrium of [`crate::hbm::preload::FromStaticEquilibrium`].
fn subtract_force_at_rest(sys: &mut MarchSystem) {
    let n = sys.n;
    let mut samples = Vec::new();
    evaluate_law(
        sys,
        1.0,
        0.0,
        &vec![0.0; n],
        &vec![0.0; sys.elements.len()],
        &mut samples,
    );
    let mut f0 = vec![0.0; n];
    add_contact_force(sys, &samples, &mut f0);
    for (h, f) in sys.force.iter_mut().zip(&f0) {
        h.mean -= f;
    }
}

/// The `log` callback of [`sector_march`] as a [`Log`]: what was read, reused or written and the
/// warnings are passed on (warnings prefixed `warning: `); the stages' details are dropped.
struct StageLog<'a>(std::cell::RefCell<&'a mut dyn FnMut(&str)>);

impl<'a> StageLog<'a> {
    fn new(log: &'a mut dyn FnMut(&str)) -> Self {
        StageLog(std::cell::RefCell::new(log))
    }

    fn line(&self, line: &str) {
        (self.0.borrow_mut())(line);
    }
}

impl Log for StageLog<'_> {
    fn info(&self, line: &str) {
        self.line(line);
    }
    fn warn(&self, line: &str) {
        self.line(&format!("warning: {line}"));
    }
    fn detail(&self, _: &str) {}
}
