//! What `nlrom run` does on a sector case, as library calls: load the case, build the FE model,
//! reduce it (Craig–Bampton, cyclic symmetry, interface reduction), place the contact pairs,
//! set up the harmonic balance problem and trace the forced response.
//!
//!     cargo run --release --example reduce_and_solve [-- CASE.toml]
//!
//! Default case: `cases/demo.toml` (the N = 8 shrouded sector with node-to-node shroud contact).
//! The command line adds the ROM file and its reuse, parallel sweep points, progress bars and the
//! results file (`nlrom::output::write_results`); see docs/user-guide.md.

use std::path::PathBuf;

use nlrom::case::Case;
use nlrom::hbm::frf::frequency_response;
use nlrom::hbm::ResponseOptions;
use nlrom::problem::sector::SectorProblem;
use nlrom::problem::settings::case_continuation;
use nlrom::{interface, model, reduction, Error};

fn main() -> nlrom::Result<()> {
    let path = std::env::args()
        .nth(1)
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("cases/demo.toml"));
    let mut log = |line: &str| eprintln!("  {line}");

    // 1. The case file: parsed and validated (every error names the file, line and key).
    let case = Case::load(&path)?;
    println!("case: {}", case.title);

    // 2. The structural model: mesh, assembled K and M, clamped groups removed.
    let structure = model::build(&case, &mut log)?;
    let mesh = structure
        .mesh
        .as_ref()
        .ok_or_else(|| Error::input("this example needs a mesh case with [reduction]"))?;

    // 3. The ROM: Craig–Bampton, then per harmonic index k_n the cyclic constraint and GSI.
    let rom = reduction::reduce(&case, &structure, &mut log)?;
    for h in &rom.harmonics {
        let lowest: Vec<String> = h
            .frequencies_hz
            .iter()
            .take(3)
            .map(|f| format!("{f:.2}"))
            .collect();
        println!(
            "ROM k = {}: {} coordinates, lowest frequencies {} Hz",
            h.harmonic_index,
            h.len(),
            lowest.join(", ")
        );
    }

    // 4. The contact pairs of every [[contact]] (SAMA or node-to-node), target placed by cyclic
    //    symmetry.
    let interfaces = interface::build_interfaces(&case, mesh, rom.cyclic.as_ref())?;
    for iface in &interfaces {
        println!(
            "contact '{}': {} elements, σ = {}",
            iface.name,
            iface.element_count(),
            iface.sigma
        );
    }

    // 5. The harmonic balance problem on the ROM (condensed on the contact DOF, forces measured
    //    from the preloaded static equilibrium) and its frequency response.
    let problem = SectorProblem::build(&case, &rom, mesh, &interfaces)?;
    let system = problem.system()?;
    let options = case_continuation(&case)?;
    let frf = frequency_response(&system, &options, &ResponseOptions::default(), &mut |_| {})?;

    // 6. The resonance: the largest first-harmonic amplitude over the reported DOF.
    let (mut best_hz, mut best_amp, mut best_dof) = (0.0, 0.0, 0);
    for p in &frf.points {
        for (r, &a) in p.response.amplitude.iter().enumerate() {
            if a > best_amp {
                (best_hz, best_amp, best_dof) = (p.omega / (2.0 * std::f64::consts::PI), a, r);
            }
        }
    }
    let dof = &problem.outputs[best_dof];
    println!(
        "{} points ({:?}); resonance {best_hz:.4} Hz, amplitude {best_amp:.6e} m at node {} \
         component {}",
        frf.points.len(),
        frf.end,
        dof.node_tag,
        dof.component
    );
    Ok(())
}
