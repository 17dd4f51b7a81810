//! The ROM file: a [`Rom`] (`src/rom.rs`) in HDF5, written by `nlrom reduce` and read by `solve`
//! and `run` (`docs/results-file.md`, `/rom/k<K>/`).
//!
//! Layout (every dataset has `unit` and `description` attributes; `docs/results-file.md`, "ROM file"):
//!
//! | path | type, shape | content |
//! |---|---|---|
//! | `/` attrs | | `program`, `version`, `file_kind = "rom"`, `title`, `case_text`, `created` |
//! | `/rom` attrs | | `key` (str), `full_dofs`, `interface_modes` (u64), `harmonic_indices` (u64 [·]), `cyclic` (i64 0/1); when cyclic: `sectors` (u64), `axis_origin` (f64 \[3\], m), `axis_direction` (f64 \[3\]), `sector_angle` (f64, rad) |
//! | `/rom/interface_frequencies_hz` | f64 \[n_if\] | CB fixed-interface eigenfrequencies (Hz) |
//! | `/rom/nodes` | compound \[n_nodes\] {tag u64, x, y, z f64} | master nodes, ascending tag, positions (m) |
//! | `/rom/groups/<name>` | u64 [·] | master node tags of the group |
//! | `/rom/k<K>` attrs | | `harmonic_index` (u64), `real` (i64 0/1) |
//! | `/rom/k<K>/stiffness`, `mass`, `damping` | f64 or complex {r, i} [n, n] | K_k (N/m), M_k (kg), C_k (N·s/m, only when defined); f64 when `real` |
//! | `/rom/k<K>/dofs` | compound \[n\] {kind enum(physical, interface, modal), node_tag u64, component u8, role enum(low_frontier, high_frontier, contact, target, keep, none), index u64} | what each reduced coordinate is |
//! | `/rom/k<K>/frequencies_hz` | f64 \[m\] | lowest eigenfrequencies of (K_k, M_k) (Hz) |
//! | `/rom/k<K>/gsi` attrs, `/rom/k<K>/gsi/dropped` | u64 [·] | present when GSI was applied: `modes_used`, `retained`; dropped mode indices |
//!
//! A real matrix is stored as f64 only when every imaginary part is +0.0, so that reading it back
//! (imaginary parts +0.0) is bitwise exact; otherwise it is stored complex.

use std::collections::BTreeMap;
use std::path::Path;

use faer::{c64, Mat};

use super::h5::{Attr, Column, Dataset, Group, H5File, H5Reader, Records};
use super::{check_file_kind, file_attributes, FileInfo};
use crate::cyclic::CyclicGeometry;
use crate::error::Result;
use crate::rom::{GsiReport, HarmonicRom, MasterNode, MasterRole, ReducedDof, Rom};

/// Root attribute `file_kind` of a ROM file.
pub const ROM_KIND: &str = "rom";

/// Labels of the `kind` enumeration of `/rom/k<K>/dofs`, by code.
const KIND_LABELS: [&str; 3] = ["physical", "interface", "modal"];
/// Labels of the `role` enumeration of `/rom/k<K>/dofs`, by code (`none` for non-physical DOFs).
const ROLE_LABELS: [&str; 6] = [
    "low_frontier",
    "high_frontier",
    "contact",
    "target",
    "keep",
    "none",
];
const ROLES: [MasterRole; 5] = [
    MasterRole::LowFrontier,
    MasterRole::HighFrontier,
    MasterRole::Contact,
    MasterRole::Target,
    MasterRole::Keep,
];
const DOF_FIELDS: [&str; 5] = ["kind", "node_tag", "component", "role", "index"];
const NODE_FIELDS: [&str; 4] = ["tag", "x", "y", "z"];

/// Writes `rom` to `path` atomically (`<path>.tmp-<pid>`, then rename), with the root attributes
/// of `info`.
pub fn write_rom(path: &Path, rom: &Rom, info: &FileInfo) -> Result<()> {
    rom_file(rom, info).write(path)
}

/// The in-memory HDF5 file of `rom` (the layout of the module documentation).
pub fn rom_file(rom: &Rom, info: &FileInfo) -> H5File {
    let mut file = H5File {
        root: file_attributes(info, ROM_KIND),
    };
    let group = file.root.group("rom");
    rom_attributes(group, rom);
    group.add(
        "interface_frequencies_hz",
        Dataset::f64s(
            rom.interface_frequencies_hz.clone(),
            "Hz",
            "eigenfrequencies of the Craig-Bampton fixed-interface modes",
        ),
    );
    group.add("nodes", nodes_dataset(&rom.nodes));
    let groups = group.group("groups");
    for (name, tags) in &rom.groups {
        groups.add(
            name,
            Dataset::u64s(tags.clone(), "1", "Gmsh tags of the group's master nodes"),
        );
    }
    for h in &rom.harmonics {
        harmonic_group(group.group(&format!("k{}", h.harmonic_index)), h);
    }
    file
}

fn rom_attributes(group: &mut Group, rom: &Rom) {
    group
        .set_attr("key", Attr::Str(rom.key.clone()))
        .set_attr("full_dofs", Attr::U64(rom.full_dofs as u64))
        .set_attr("interface_modes", Attr::U64(rom.interface_modes as u64))
        .set_attr(
            "harmonic_indices",
            Attr::U64s(
                rom.harmonics
                    .iter()
                    .map(|h| h.harmonic_index as u64)
                    .collect(),
            ),
        )
        .set_attr("cyclic", Attr::I64(i64::from(rom.cyclic.is_some())));
    if let Some(c) = &rom.cyclic {
        group
            .set_attr("sectors", Attr::U64(c.sectors as u64))
            .set_attr("axis_origin", Attr::F64s(c.origin.to_vec()))
            .set_attr("axis_direction", Attr::F64s(c.axis.to_vec()))
            .set_attr("sector_angle", Attr::F64(c.alpha));
    }
}

fn nodes_dataset(nodes: &[MasterNode]) -> Dataset {
    let coordinate = |c: usize| Column::F64(nodes.iter().map(|n| n.position[c]).collect());
    let records = Records::new()
        .column("tag", Column::U64(nodes.iter().map(|n| n.tag).collect()))
        .column("x", coordinate(0))
        .column("y", coordinate(1))
        .column("z", coordinate(2));
    Dataset::records(
        records,
        "m",
        "master nodes: Gmsh tag and position (m), ascending tag",
    )
}

fn harmonic_group(group: &mut Group, h: &HarmonicRom) {
    group
        .set_attr("harmonic_index", Attr::U64(h.harmonic_index as u64))
        .set_attr("real", Attr::I64(i64::from(h.real)));
    let k = h.harmonic_index;
    group.add(
        "stiffness",
        matrix_dataset(
            &h.stiffness,
            h.real,
            "N/m",
            &format!("reduced stiffness K_{k}, Hermitian"),
        ),
    );
    group.add(
        "mass",
        matrix_dataset(
            &h.mass,
            h.real,
            "kg",
            &format!("reduced mass M_{k}, Hermitian"),
        ),
    );
    if let Some(c) = &h.damping {
        group.add(
            "damping",
            matrix_dataset(
                c,
                h.real,
                "N*s/m",
                &format!("reduced damping C_{k}, Hermitian"),
            ),
        );
    }
    group.add("dofs", dofs_dataset(&h.dofs));
    group.add(
        "frequencies_hz",
        Dataset::f64s(
            h.frequencies_hz.clone(),
            "Hz",
            &format!("lowest eigenfrequencies of (K_{k}, M_{k}), ascending"),
        ),
    );
    if let Some(gsi) = &h.gsi {
        let g = group.group("gsi");
        g.set_attr("modes_used", Attr::U64(gsi.modes_used as u64))
            .set_attr("retained", Attr::U64(gsi.retained as u64));
        g.add(
            "dropped",
            Dataset::u64s(
                gsi.dropped.iter().map(|&d| d as u64).collect(),
                "1",
                "0-based indices of the GSI mode vectors dropped as linearly dependent",
            ),
        );
    }
}

/// A matrix as f64 when it is real with all imaginary parts +0.0, else as complex.
fn matrix_dataset(m: &Mat<c64>, real: bool, unit: &str, description: &str) -> Dataset {
    let positive_zero_imaginary =
        (0..m.ncols()).all(|j| (0..m.nrows()).all(|i| m[(i, j)].im.to_bits() == 0));
    if real && positive_zero_imaginary {
        let re = Mat::<f64>::from_fn(m.nrows(), m.ncols(), |i, j| m[(i, j)].re);
        Dataset::real_matrix(&re, unit, description)
    } else {
        Dataset::complex_matrix(m, unit, description)
    }
}

fn dofs_dataset(dofs: &[ReducedDof]) -> Dataset {
    let none_role = (ROLE_LABELS.len() - 1) as u8;
    let mut kind = Vec::with_capacity(dofs.len());
    let mut tag = Vec::with_capacity(dofs.len());
    let mut component = Vec::with_capacity(dofs.len());
    let mut role = Vec::with_capacity(dofs.len());
    let mut index = Vec::with_capacity(dofs.len());
    for dof in dofs {
        let (k, t, c, r, i) = match *dof {
            ReducedDof::Physical {
                node_tag,
                component,
                role,
            } => (0, node_tag, component, role_code(role), 0),
            ReducedDof::Interface { index } => (1, 0, 0, none_role, index as u64),
            ReducedDof::Modal { mode } => (2, 0, 0, none_role, mode as u64),
        };
        kind.push(k);
        tag.push(t);
        component.push(c);
        role.push(r);
        index.push(i);
    }
    let labels = |l: &[&str]| l.iter().map(|s| s.to_string()).collect::<Vec<_>>();
    let records = Records::new()
        .column(
            "kind",
            Column::Enum {
                labels: labels(&KIND_LABELS),
                codes: kind,
            },
        )
        .column("node_tag", Column::U64(tag))
        .column("component", Column::U8(component))
        .column(
            "role",
            Column::Enum {
                labels: labels(&ROLE_LABELS),
                codes: role,
            },
        )
        .column("index", Column::U64(index));
    Dataset::records(
        records,
        "1",
        "reduced coordinates in matrix order: kind; for physical DOFs the Gmsh node tag, component (0/1/2 = x/y/z) and master role; for interface and modal coordinates the 0-based index",
    )
}

fn role_code(role: MasterRole) -> u8 {
    ROLES.iter().position(|r| *r == role).unwrap_or(0) as u8
}

/// Reads a ROM file written by [`write_rom`]. Errors (exit status 2) name the file and the group,
/// dataset or attribute: not an nlrom ROM file, a missing group or dataset, a wrong shape or type.
pub fn read_rom(path: &Path) -> Result<Rom> {
    let reader = H5Reader::open(path)?;
    check_file_kind(&reader, ROM_KIND)?;
    if !reader.has_group("/rom") {
        return Err(reader.error("/rom", "missing group; the file holds no ROM"));
    }
    let full_dofs = reader.attr_u64("/rom", "full_dofs")? as usize;
    let interface_modes = reader.attr_u64("/rom", "interface_modes")? as usize;
    let key = reader.attr_str("/rom", "key")?;
    let cyclic = read_cyclic(&reader)?;
    let interface_frequencies_hz = reader.f64_vector("/rom/interface_frequencies_hz")?;
    let nodes = read_nodes(&reader)?;
    let groups = read_groups(&reader)?;
    let harmonics = read_harmonics(&reader)?;
    Ok(Rom {
        cyclic,
        full_dofs,
        nodes,
        groups,
        interface_modes,
        interface_frequencies_hz,
        harmonics,
        key,
    })
}

fn read_cyclic(reader: &H5Reader) -> Result<Option<CyclicGeometry>> {
    if reader.attr_i64("/rom", "cyclic")? == 0 {
        return Ok(None);
    }
    let sectors = reader.attr_u64("/rom", "sectors")? as usize;
    if sectors < 2 {
        return Err(reader.error("/rom", format!("attribute sectors = {sectors}, need ≥ 2")));
    }
    let origin = reader.attr_f64s("/rom", "axis_origin", 3)?;
    let axis = reader.attr_f64s("/rom", "axis_direction", 3)?;
    Ok(Some(CyclicGeometry {
        sectors,
        origin: [origin[0], origin[1], origin[2]],
        axis: [axis[0], axis[1], axis[2]],
        alpha: reader.attr_f64("/rom", "sector_angle")?,
    }))
}

fn read_nodes(reader: &H5Reader) -> Result<Vec<MasterNode>> {
    let path = "/rom/nodes";
    let records = reader.records(path, None, &NODE_FIELDS)?;
    let tags = u64_column(reader, path, &records, "tag")?;
    let coordinate = |name| reader.column(path, &records, name, Column::as_f64, "f64");
    let xyz = [coordinate("x")?, coordinate("y")?, coordinate("z")?];
    Ok(tags
        .iter()
        .enumerate()
        .map(|(j, &tag)| MasterNode {
            tag,
            position: [xyz[0][j], xyz[1][j], xyz[2][j]],
        })
        .collect())
}

fn read_groups(reader: &H5Reader) -> Result<BTreeMap<String, Vec<u64>>> {
    let mut groups = BTreeMap::new();
    if !reader.has_group("/rom/groups") {
        return Err(reader.error("/rom/groups", "missing group"));
    }
    let group = reader.group("/rom/groups")?;
    for name in group.datasets.keys() {
        let tags = reader.u64_vector(&format!("/rom/groups/{name}"))?;
        groups.insert(name.clone(), tags);
    }
    Ok(groups)
}

fn read_harmonics(reader: &H5Reader) -> Result<Vec<HarmonicRom>> {
    let indices = match reader.attr("/rom", "harmonic_indices")? {
        Attr::U64s(v) => v,
        other => {
            return Err(reader.error(
                "/rom",
                format!("attribute harmonic_indices should be unsigned integers, found {other:?}"),
            ))
        }
    };
    let mut harmonics = Vec::with_capacity(indices.len());
    for k in indices {
        harmonics.push(read_harmonic(reader, k as usize)?);
    }
    harmonics.sort_by_key(|h| h.harmonic_index);
    Ok(harmonics)
}

fn read_harmonic(reader: &H5Reader, k: usize) -> Result<HarmonicRom> {
    let base = format!("/rom/k{k}");
    if !reader.has_group(&base) {
        return Err(reader.error(&base, "missing group (listed in /rom harmonic_indices)"));
    }
    let index = reader.attr_u64(&base, "harmonic_index")? as usize;
    if index != k {
        return Err(reader.error(
            &base,
            format!("attribute harmonic_index = {index}, expected {k}"),
        ));
    }
    let real = reader.attr_i64(&base, "real")? != 0;
    let dofs = read_dofs(reader, &format!("{base}/dofs"))?;
    let n = dofs.len();
    let matrix = |name: &str| -> Result<Mat<c64>> {
        let path = format!("{base}/{name}");
        let values = reader.complexes(&path, &[n, n])?;
        Ok(Mat::from_fn(n, n, |i, j| values[i * n + j]))
    };
    let stiffness = matrix("stiffness")?;
    let mass = matrix("mass")?;
    let group = reader.group(&base)?;
    let damping = if group.datasets.contains_key("damping") {
        Some(matrix("damping")?)
    } else {
        None
    };
    let frequencies_hz = reader.f64_vector(&format!("{base}/frequencies_hz"))?;
    let gsi = if group.groups.contains_key("gsi") {
        let path = format!("{base}/gsi");
        Some(GsiReport {
            modes_used: reader.attr_u64(&path, "modes_used")? as usize,
            retained: reader.attr_u64(&path, "retained")? as usize,
            dropped: reader
                .u64_vector(&format!("{path}/dropped"))?
                .into_iter()
                .map(|d| d as usize)
                .collect(),
        })
    } else {
        None
    };
    Ok(HarmonicRom {
        harmonic_index: k,
        real,
        stiffness,
        mass,
        damping,
        dofs,
        frequencies_hz,
        gsi,
    })
}

fn read_dofs(reader: &H5Reader, path: &str) -> Result<Vec<ReducedDof>> {
    let records = reader.records(path, None, &DOF_FIELDS)?;
    let kind = enum_column(reader, path, &records, "kind", &KIND_LABELS)?;
    let tag = u64_column(reader, path, &records, "node_tag")?;
    let component = match records.get("component") {
        Some(Column::U8(v)) => v.clone(),
        _ => return Err(reader.error(path, "field \"component\" should be u8")),
    };
    let role = enum_column(reader, path, &records, "role", &ROLE_LABELS)?;
    let index = u64_column(reader, path, &records, "index")?;
    let mut dofs = Vec::with_capacity(records.len());
    for j in 0..records.len() {
        let dof = match kind[j] {
            0 => {
                let Some(&role) = ROLES.get(role[j] as usize) else {
                    return Err(reader.error(
                        path,
                        format!("record {j}: physical DOF without a master role"),
                    ));
                };
                if component[j] > 2 {
                    return Err(
                        reader.error(path, format!("record {j}: component {} > 2", component[j]))
                    );
                }
                ReducedDof::Physical {
                    node_tag: tag[j],
                    component: component[j],
                    role,
                }
            }
            1 => ReducedDof::Interface {
                index: index[j] as usize,
            },
            _ => ReducedDof::Modal {
                mode: index[j] as usize,
            },
        };
        dofs.push(dof);
    }
    Ok(dofs)
}

fn u64_column<'a>(
    reader: &H5Reader,
    path: &str,
    records: &'a Records,
    name: &str,
) -> Result<&'a [u64]> {
    reader.column(path, records, name, Column::as_u64, "u64")
}

/// The codes of the enum field `name`, whose labels must be `labels`.
fn enum_column<'a>(
    reader: &H5Reader,
    path: &str,
    records: &'a Records,
    name: &str,
    labels: &[&str],
) -> Result<&'a [u8]> {
    match records.get(name) {
        Some(Column::Enum { labels: l, codes })
            if l.iter().map(String::as_str).eq(labels.iter().copied()) =>
        {
            Ok(codes)
        }
        _ => Err(reader.error(
            path,
            format!("field {name:?} should be the enumeration {labels:?}"),
        )),
    }
}
