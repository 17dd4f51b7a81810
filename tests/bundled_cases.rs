//! Every case file bundled in `cases/`, `cases/paper/` and `cases/nlvib/` (the cases users start from, and the
//! ones the documentation's commands run) parses and validates, and every group it names exists in its
//! mesh.

use std::path::{Path, PathBuf};

use nlrom::case::Case;
use nlrom::mesh::msh::read_msh;

fn case_files(dir: &Path) -> Vec<PathBuf> {
    let mut files: Vec<PathBuf> = std::fs::read_dir(dir)
        .expect("cases folder")
        .map(|e| e.expect("entry").path())
        .filter(|p| p.extension().is_some_and(|e| e == "toml"))
        .collect();
    files.sort();
    files
}

#[test]
fn every_bundled_case_loads_and_its_groups_exist() {
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    let mut files = case_files(&root.join("cases"));
    files.extend(case_files(&root.join("cases/paper")));
    let nlvib = case_files(&root.join("cases/nlvib"));
    // NLvib's example 07 chain (two variants), the SDOF Jenkins oscillator, the example 08 beam
    assert!(nlvib.len() >= 4, "{nlvib:?}");
    files.extend(nlvib);
    // 8 cases in cases/, 3 models × 2 modes + the finer-target variant in cases/paper/
    assert!(files.len() >= 15, "{files:?}");
    let mut with_mesh = 0;
    for path in &files {
        let case = Case::load(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        if let Some(mesh_path) = &case.model.mesh {
            let mesh = read_msh(mesh_path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
            case.check_groups(&mesh)
                .unwrap_or_else(|e| panic!("{}: {e}", path.display()));
            with_mesh += 1;
        }
    }
    assert!(with_mesh >= 12, "{with_mesh} cases with a mesh");
}
