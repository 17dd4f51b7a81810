//! `nlrom export`: K and M of the free (clamped) model as symmetric Matrix Market files and the
//! DOF map of their rows (`dofs.csv`).

use std::path::Path;

use super::Reporter;
use crate::case::Case;
use crate::error::{Error, Result};
use crate::matrix_io::{write_dof_map, write_matrix_market_symmetric};
use crate::model;

/// `nlrom export`: K and M of the free (clamped) model as symmetric Matrix Market files and the
/// DOF map of their rows.
pub fn export_command(case_path: &Path, dir: &Path, rep: &Reporter) -> Result<()> {
    let case = Case::load(case_path)?;
    let model = model::build(&case, &mut |l| rep.detail(l))?;
    std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, e))?;
    write_matrix_market_symmetric(&dir.join("K.mtx"), &model.free.k)?;
    write_matrix_market_symmetric(&dir.join("M.mtx"), &model.free.m)?;
    let mut written = vec!["K.mtx", "M.mtx"];
    if let Some(map) = model.free_dof_map() {
        write_dof_map(&dir.join("dofs.csv"), &map)?;
        written.push("dofs.csv");
    }
    rep.info(&format!(
        "wrote {} in {} ({} free DOF)",
        written.join(", "),
        dir.display(),
        model.free.n_free()
    ));
    Ok(())
}
