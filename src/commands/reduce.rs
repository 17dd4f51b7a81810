//! `nlrom reduce`: the ROM of a mesh case for every harmonic index it needs, written to an HDF5
//! ROM file that `nlrom solve` and `nlrom run` reuse while its key matches.

use std::path::Path;
use std::time::Instant;

use serde_json::{json, Value};

use super::Reporter;
use crate::case::Case;
use crate::error::{Error, Result};
use crate::model;
use crate::output::write_rom;
use crate::problem::rom_store::{create_parent, file_info};
use crate::reduction::reduce;

/// `nlrom reduce CASE -o ROM.h5`: builds the model, reduces it for every harmonic index the case
/// needs and writes the ROM file (atomically); prints the harmonic indices, their number of
/// coordinates and lowest frequencies.
pub fn reduce_command(
    case_path: &Path,
    output: &Path,
    rep: &Reporter,
    as_json: bool,
) -> Result<()> {
    let start = Instant::now();
    let case = Case::load(case_path)?;
    if case.model.mesh.is_none() {
        return Err(Error::input(format!(
            "{}: `nlrom reduce` needs a mesh case (`[model] mesh` with `[reduction]`); a matrix case is solved directly by `nlrom solve`",
            case_path.display()
        )));
    }
    let model = model::build(&case, &mut |l| rep.detail(l))?;
    let rom = reduce(&case, &model, &mut |l| rep.detail(l))?;
    create_parent(output)?;
    write_rom(output, &rom, &file_info(&case))?;
    rep.info(&format!("wrote {} (key {})", output.display(), rom.key));
    let harmonics: Vec<Value> = rom
        .harmonics
        .iter()
        .map(|h| {
            json!({
                "harmonic_index": h.harmonic_index,
                "coordinates": h.len(),
                "frequencies_hz": h.frequencies_hz,
            })
        })
        .collect();
    if as_json {
        let report = json!({
            "output": output.display().to_string(),
            "key": rom.key,
            "full_dofs": rom.full_dofs,
            "interface_modes": rom.interface_modes,
            "harmonics": harmonics,
            "wall_seconds": start.elapsed().as_secs_f64(),
        });
        println!("{report}");
        return Ok(());
    }
    println!(
        "ROM of {} ({} free DOF, {} interface modes) written to {}",
        case_path.display(),
        rom.full_dofs,
        rom.interface_modes,
        output.display()
    );
    println!("{:>6} {:>12}  lowest frequencies (Hz)", "k", "coordinates");
    for h in &rom.harmonics {
        let f: Vec<String> = h
            .frequencies_hz
            .iter()
            .take(5)
            .map(|f| format!("{f:.3}"))
            .collect();
        println!("{:>6} {:>12}  {}", h.harmonic_index, h.len(), f.join(", "));
    }
    Ok(())
}
