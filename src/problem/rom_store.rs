//! The ROM of a sector case: read from a ROM file whose stored key equals
//! [`rom_key`] of the case (the mesh or matrix files' bytes and the model, cyclic, reduction and
//! contact-group settings), else reduced ([`crate::reduction::reduce`]) and, with
//! [`RomPolicy::Cache`], written there for the next run.
//!
//! [`RomPolicy::Shared`] is a content-addressed cache directory, `DIR/<key>.rom.h5`, which many
//! cases, threads and processes (the array tasks of a cluster job on a shared file system) use at
//! once: cases with the same key reduce once; when several reduce the same key at the same time,
//! the first to publish its file wins ([`publish_once`]: a hard link that fails when the file
//! exists, never a partial file) and the others read the winner's file, so every case solves
//! with the same ROM.

use std::path::{Path, PathBuf};
use std::time::Instant;

use super::Log;
use crate::case::Case;
use crate::error::{Error, Result};
use crate::mesh::msh::read_msh;
use crate::mesh::Mesh;
use crate::model;
use crate::output::h5::{publish_once, Published};
use crate::output::rom_file::rom_file;
use crate::output::{read_rom, write_rom, FileInfo};
use crate::reduction::{reduce, rom_key};
use crate::rom::Rom;

/// Where the ROM of a sector case comes from.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum RomPolicy {
    /// `nlrom solve`: read the case's `[rom] file` when its stored key equals [`rom_key`] of the
    /// case, else reduce in memory (nothing is written).
    ReadIfMatching,
    /// `nlrom run`, `batch`, `demo`: read this ROM file when its key matches, else reduce and
    /// write it there.
    Cache(PathBuf),
    /// `nlrom batch`: the content-addressed cache directory; the ROM file is `DIR/<key>.rom.h5`
    /// (module documentation).
    Shared(PathBuf),
}

/// How the ROM of a sector case was obtained.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum RomOrigin {
    /// Read from this file (its key matched).
    Reused(PathBuf),
    /// Reduced now; written to the file if any.
    Reduced(Option<PathBuf>),
    /// Reduced now, but another task published the same key's file first: the ROM was read
    /// from that file.
    Raced(PathBuf),
}

/// The ROM of a sector case per `policy`, the sector mesh, and where the ROM came from.
pub fn sector_rom(
    case: &Case,
    policy: &RomPolicy,
    log: &dyn Log,
) -> Result<(Rom, Mesh, RomOrigin)> {
    let key = rom_key(case)?;
    let (file, cache) = match policy {
        RomPolicy::ReadIfMatching => (case.rom.as_ref().map(|r| r.file.clone()), false),
        RomPolicy::Cache(p) => (Some(p.clone()), true),
        RomPolicy::Shared(dir) => (Some(shared_rom_file(dir, &key)), true),
    };
    if let Some(path) = &file {
        if path.exists() {
            match read_rom(path) {
                Ok(rom) if rom.key == key => {
                    log.info(&format!(
                        "reusing the ROM in {} (key {key}: mesh, material, reduction and contact groups unchanged)",
                        path.display()
                    ));
                    let mesh = read_mesh(case)?;
                    return Ok((rom, mesh, RomOrigin::Reused(path.clone())));
                }
                Ok(rom) => log.info(&format!(
                    "the ROM in {} was built from other inputs (key {} ≠ {key}); reducing again",
                    path.display(),
                    rom.key
                )),
                Err(e) => log.warn(&format!(
                    "cannot use the ROM file {}: {e}; reducing again",
                    path.display()
                )),
            }
        } else if !cache {
            log.warn(&format!(
                "[rom] file {} does not exist; reducing (write it with `nlrom reduce`)",
                path.display()
            ));
        }
    }
    // a file that is there but unusable is replaced below, not raced for
    let stale = file.as_ref().is_some_and(|p| p.exists());
    let t = Instant::now();
    log.info("reducing the model (Craig–Bampton, cyclic symmetry, interface reduction)");
    let mut model = model::build(case, &mut |l| log.detail(l))?;
    let rom = reduce(case, &model, &mut |l| log.detail(l))?;
    log.info(&format!(
        "ROM of harmonic indices {:?} in {:.2} s",
        rom.harmonics
            .iter()
            .map(|h| h.harmonic_index)
            .collect::<Vec<_>>(),
        t.elapsed().as_secs_f64()
    ));
    let mesh = model.mesh.take().ok_or_else(|| {
        Error::input(format!(
            "{}: a sector case needs `[model] mesh`",
            case.path.display()
        ))
    })?;
    if let (RomPolicy::Shared(_), Some(path), false) = (policy, &file, stale) {
        create_parent(path)?;
        let bytes = rom_file(&rom, &file_info(case)).to_bytes()?;
        return match publish_once(path, &bytes)? {
            Published::Created => {
                log.info(&format!("wrote the ROM to {} (key {key})", path.display()));
                Ok((rom, mesh, RomOrigin::Reduced(Some(path.clone()))))
            }
            Published::Existing => {
                let winner = read_rom(path)?;
                if winner.key != key {
                    return Err(Error::Compute(format!(
                        "the ROM cache file {} holds key {} instead of {key}",
                        path.display(),
                        winner.key
                    )));
                }
                log.info(&format!(
                    "another task wrote {} first (key {key}); using its ROM",
                    path.display()
                ));
                Ok((winner, mesh, RomOrigin::Raced(path.clone())))
            }
        };
    }
    let written = if cache { file } else { None };
    if let Some(path) = &written {
        create_parent(path)?;
        write_rom(path, &rom, &file_info(case))?;
        log.info(&format!("wrote the ROM to {} (key {key})", path.display()));
    }
    Ok((rom, mesh, RomOrigin::Reduced(written)))
}

/// The file of ROM key `key` in the content-addressed cache directory `dir`: `dir/<key>.rom.h5`.
pub fn shared_rom_file(dir: &Path, key: &str) -> PathBuf {
    dir.join(format!("{key}.rom.h5"))
}

/// The title and text of a case for the files it writes.
pub fn file_info(case: &Case) -> FileInfo {
    FileInfo {
        title: case.title.clone(),
        case_text: case.source_text.clone(),
    }
}

/// The case's mesh, with its groups checked against the case.
fn read_mesh(case: &Case) -> Result<Mesh> {
    let path = case.model.mesh.as_ref().ok_or_else(|| {
        Error::input(format!(
            "{}: a sector case needs `[model] mesh`",
            case.path.display()
        ))
    })?;
    let mesh = read_msh(path)?;
    case.check_groups(&mesh)?;
    Ok(mesh)
}

/// Creates the parent directory of `path` if it is missing.
pub fn create_parent(path: &Path) -> Result<()> {
    match path.parent() {
        Some(dir) if !dir.as_os_str().is_empty() => {
            std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, e))
        }
        _ => Ok(()),
    }
}
