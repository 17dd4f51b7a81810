#!/usr/bin/env python3
"""Cross-check nlrom's Gmsh reader against meshio on every bundled mesh.

    python3 tools/validation/meshio_compare.py --write tests/data/meshio_counts.json
        Read every .msh in meshes/ and meshes/formats/ with meshio and write the reference counts.

    python3 tools/validation/meshio_compare.py --check [--nlrom target/release/nlrom] [--reference JSON] [FILE ...]
        Run `nlrom mesh info FILE --json` on every mesh (or the FILEs given) and compare the node
        count, the element count per type, the physical groups (name, dim, tag, elements, nodes),
        the format/binary flags and the bounding box against meshio (read now, or taken from
        --reference, e.g. tests/data/meshio_counts.json, when meshio is not at hand). Prints a
        table; the exit status is 1 on any mismatch or nlrom failure.

Reference record, one per file, keyed by the path relative to the repository root:

    {"nodes": int, "elements": {"tetra10": n, ...},
     "groups": {"<name>": {"dim": d, "tag": t, "elements": e, "nodes": m}},
     "bbox": [[xmin, ymin, zmin], [xmax, ymax, zmax]]}

* "nodes" is the number of nodes listed in the $Nodes section. meshio 5.3.5 keeps every node of the
  file (it neither prunes unused nodes nor merges duplicates, for 2.2 and 4.1 alike); the script
  nevertheless reads the count from the $Nodes header itself and fails loudly if meshio disagrees.
* "elements" counts every element in the file per nlrom type name; "groups" counts the elements that
  carry the group's physical tag in the group's dimension ("nodes" = distinct nodes they use).
  meshio keeps only the FIRST physical tag of an element (MSH 4.1: of its entity), which is exact
  for the bundled meshes: no entity belongs to two physical groups of the same dimension.
* "bbox" is over all nodes of the file.
"""

from __future__ import annotations

import argparse
import json
import re
import struct
import subprocess
import sys
import warnings
from pathlib import Path

REPO = Path(__file__).resolve().parents[2]
DEFAULT_NLROM = REPO / "target" / "release" / "nlrom"

# meshio cell type -> (nlrom type name, dimension)
MESHIO_TO_NLROM = {
    "vertex": ("point", 0),
    "line": ("line2", 1),
    "line3": ("line3", 1),
    "triangle": ("triangle3", 2),
    "triangle6": ("triangle6", 2),
    "quad": ("quad4", 2),
    "quad8": ("quad8", 2),
    "quad9": ("quad9", 2),
    "tetra": ("tetra4", 3),
    "tetra10": ("tetra10", 3),
    "hexahedron": ("hexa8", 3),
    "hexahedron20": ("hexa20", 3),
    "hexahedron27": ("hexa27", 3),
    "wedge": ("prism6", 3),
    "wedge15": ("prism15", 3),
    "wedge18": ("prism18", 3),
    "pyramid": ("pyramid5", 3),
    "pyramid13": ("pyramid13", 3),
    "pyramid14": ("pyramid14", 3),
}


def mesh_files() -> list[Path]:
    files = sorted((REPO / "meshes").glob("*.msh")) + sorted((REPO / "meshes" / "formats").glob("*.msh"))
    return files


def rel(path: Path) -> str:
    try:
        return path.resolve().relative_to(REPO).as_posix()
    except ValueError:
        return str(path)


# ------------------------------------------------------------------------------------------------
# direct header reading (independent of meshio)
# ------------------------------------------------------------------------------------------------


def read_header(path: Path) -> dict:
    """Format version, binary flag and the node / element totals from the section headers."""
    data = path.read_bytes()
    m = re.search(rb"\$MeshFormat\r?\n([^\n]*)\n", data)
    if not m:
        raise ValueError(f"{path}: no $MeshFormat")
    version, ftype, dsize = m.group(1).split()[:3]
    version = version.decode()
    binary = int(ftype) == 1
    dsize = int(dsize)
    out = {"format": version, "binary": binary}
    size_t = {4: "I", 8: "Q"}[dsize]
    endian = "<"
    if binary:
        # a binary int 1 follows the format line: it tells the byte order
        one = data[m.end():m.end() + 4]
        endian = "<" if struct.unpack("<i", one)[0] == 1 else ">"
    for section, key in ((b"Nodes", "nodes"), (b"Elements", "elements")):
        s = re.search(rb"(?:^|\n)\$" + section + rb"\r?\n", data)
        if not s:
            raise ValueError(f"{path}: no ${section.decode()}")
        pos = s.end()
        if version.startswith("4"):
            if binary:
                # numEntityBlocks numNodes minTag maxTag, all size_t
                vals = struct.unpack(endian + "4" + size_t, data[pos:pos + 4 * dsize])
                out[key] = int(vals[1])
            else:
                out[key] = int(data[pos:data.index(b"\n", pos)].split()[1])
        else:  # 2.x: the count is an ASCII line in both ASCII and binary files
            out[key] = int(data[pos:data.index(b"\n", pos)].split()[0])
    return out


# ------------------------------------------------------------------------------------------------
# meshio reference
# ------------------------------------------------------------------------------------------------


def meshio_record(path: Path) -> tuple[dict, list[str]]:
    """Reference record of one file from meshio; also returns notes on meshio vs the headers."""
    import numpy as np
    import meshio
    import meshio._mesh

    # meshio 5.3.5 reads Gmsh's 15-node prism and 13-node pyramid but has no topological dimension
    # for them (CellBlock raises KeyError 'wedge15'); supply it.
    meshio._mesh.topological_dimension.setdefault("wedge15", 3)
    meshio._mesh.topological_dimension.setdefault("pyramid13", 3)

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        m = meshio.read(str(path), file_format="gmsh")
    header = read_header(path)
    notes = []

    elements: dict[str, int] = {}
    for block in m.cells:
        if block.type not in MESHIO_TO_NLROM:
            raise ValueError(f"{path}: meshio cell type {block.type!r} has no nlrom name")
        name = MESHIO_TO_NLROM[block.type][0]
        elements[name] = elements.get(name, 0) + len(block.data)

    n_nodes = len(m.points)
    if n_nodes != header["nodes"]:
        notes.append(f"meshio has {n_nodes} points, the $Nodes header {header['nodes']}: using the header")
        n_nodes = header["nodes"]
    n_elem = sum(elements.values())
    if n_elem != header["elements"]:
        notes.append(f"meshio has {n_elem} cells, the $Elements header {header['elements']}")

    groups: dict[str, dict] = {}
    phys = m.cell_data.get("gmsh:physical")
    for gname, (tag, dim) in sorted(m.field_data.items(), key=lambda kv: (int(kv[1][1]), int(kv[1][0]))):
        tag, dim = int(tag), int(dim)
        count = 0
        used = []
        if phys is not None:
            for block, ptags in zip(m.cells, phys):
                if MESHIO_TO_NLROM[block.type][1] != dim:
                    continue
                sel = np.asarray(ptags) == tag
                if sel.any():
                    count += int(sel.sum())
                    used.append(np.unique(block.data[sel]))
        nodes = int(len(np.unique(np.concatenate(used)))) if used else 0
        groups[gname] = {"dim": dim, "tag": tag, "elements": count, "nodes": nodes}

    pts = np.asarray(m.points, dtype=float)
    if pts.shape[1] == 2:
        pts = np.hstack([pts, np.zeros((len(pts), 1))])
    bbox = [pts.min(axis=0).tolist(), pts.max(axis=0).tolist()] if len(pts) else [[0.0] * 3, [0.0] * 3]
    return {"nodes": n_nodes, "elements": dict(sorted(elements.items())), "groups": groups,
            "bbox": bbox}, notes


def format_reference(result: dict) -> str:
    """JSON text of the reference, one line per element table / group / bbox (diff-friendly)."""
    d = json.dumps
    lines = ["{"]
    for i, (key, rec) in enumerate(result.items()):
        lines.append(f" {d(key)}: {{")
        lines.append(f"  \"nodes\": {rec['nodes']},")
        lines.append(f"  \"elements\": {d(rec['elements'])},")
        lines.append("  \"groups\": {")
        groups = list(rec["groups"].items())
        for j, (name, g) in enumerate(groups):
            lines.append(f"   {d(name)}: {d(g)}" + ("," if j + 1 < len(groups) else ""))
        lines.append("  },")
        lines.append(f"  \"bbox\": {d(rec['bbox'])}")
        lines.append(" }" + ("," if i + 1 < len(result) else ""))
    lines.append("}")
    text = "\n".join(lines) + "\n"
    assert json.loads(text) == result
    return text


def cmd_write(out: Path) -> int:
    result = {}
    for path in mesh_files():
        rec, notes = meshio_record(path)
        result[rel(path)] = rec
        for n in notes:
            print(f"NOTE {rel(path)}: {n}")
        print(f"{rel(path):50s} nodes={rec['nodes']:7d}  " +
              " ".join(f"{k}={v}" for k, v in rec["elements"].items()))
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(format_reference(result))
    print(f"wrote {rel(out)} ({len(result)} files)")
    return 0


# ------------------------------------------------------------------------------------------------
# comparison with nlrom
# ------------------------------------------------------------------------------------------------


def run_nlrom(nlrom: Path, path: Path, timeout: float) -> dict:
    proc = subprocess.run([str(nlrom), "mesh", "info", str(path), "--json"], cwd=REPO,
                          capture_output=True, text=True, timeout=timeout)
    if proc.returncode != 0:
        raise RuntimeError(f"exit status {proc.returncode}: {proc.stderr.strip()[-500:]}")
    try:
        return json.loads(proc.stdout)
    except json.JSONDecodeError as e:
        raise RuntimeError(f"invalid JSON on stdout ({e}): {proc.stdout[:200]!r}") from None


def compare(ref: dict, got: dict, header: dict | None) -> list[str]:
    """List of differences (empty = match)."""
    diffs = []
    if header is not None:
        if str(got.get("format")) != header["format"]:
            diffs.append(f"format: file {header['format']} nlrom {got.get('format')!r}")
        if got.get("binary") is not header["binary"]:
            diffs.append(f"binary: file {header['binary']} nlrom {got.get('binary')!r}")
    if got.get("nodes") != ref["nodes"]:
        diffs.append(f"nodes: meshio {ref['nodes']} nlrom {got.get('nodes')}")
    got_el = got.get("elements") or {}
    for t in sorted(set(ref["elements"]) | set(got_el)):
        a, b = ref["elements"].get(t, 0), got_el.get(t, 0)
        if a != b:
            diffs.append(f"elements[{t}]: meshio {a} nlrom {b}")
    got_groups = {}
    for g in got.get("groups") or []:
        if g.get("name") in got_groups:
            diffs.append(f"group {g.get('name')!r} listed twice by nlrom")
        got_groups[g.get("name")] = g
    for name in sorted(set(ref["groups"]) | set(got_groups)):
        if name not in got_groups:
            diffs.append(f"group {name!r}: missing in nlrom")
            continue
        if name not in ref["groups"]:
            diffs.append(f"group {name!r}: not in meshio")
            continue
        for key in ("dim", "tag", "elements", "nodes"):
            a, b = ref["groups"][name][key], got_groups[name].get(key)
            if a != b:
                diffs.append(f"group {name!r} {key}: meshio {a} nlrom {b}")
    rb, gb = ref.get("bbox"), got.get("bbox")
    if rb is not None:
        try:
            size = max(rb[1][i] - rb[0][i] for i in range(3)) or 1.0
            worst = max(abs(rb[j][i] - gb[j][i]) for j in range(2) for i in range(3))
            if not worst <= 1e-12 * size:
                diffs.append(f"bbox: meshio {rb} nlrom {gb}")
        except (TypeError, IndexError, KeyError):
            diffs.append(f"bbox: malformed in nlrom output: {gb!r}")
    return diffs


def cmd_check(nlrom: Path, reference: Path | None, files: list[Path], timeout: float, verbose: bool) -> int:
    if not nlrom.exists():
        print(f"nlrom binary not found: {nlrom} (build it with `cargo build --release`)", file=sys.stderr)
        return 2
    refs = json.loads(reference.read_text()) if reference else None
    paths = files or mesh_files()
    if not paths:
        print("no mesh files found", file=sys.stderr)
        return 2
    failures = 0
    width = max(len(rel(p)) for p in paths)
    print(f"{'file':{width}s}  {'nodes':>8s}  {'elems':>8s}  {'groups':>6s}  result")
    for path in paths:
        key = rel(path)
        try:
            if refs is not None:
                if key not in refs:
                    raise RuntimeError(f"not in the reference {rel(reference)}")
                ref = refs[key]
            else:
                ref, _ = meshio_record(path)
            header = read_header(path)
            got = run_nlrom(nlrom, path, timeout)
            diffs = compare(ref, got, header)
        except Exception as e:  # noqa: BLE001 - reported as a failure of this file
            failures += 1
            print(f"{key:{width}s}  {'':>8s}  {'':>8s}  {'':>6s}  ERROR {e}")
            continue
        n_el = sum(ref["elements"].values())
        status = "ok" if not diffs else f"MISMATCH ({len(diffs)})"
        print(f"{key:{width}s}  {ref['nodes']:8d}  {n_el:8d}  {len(ref['groups']):6d}  {status}")
        if diffs:
            failures += 1
            for d in diffs:
                print(f"{'':{width}s}    - {d}")
        elif verbose:
            print(f"{'':{width}s}    {json.dumps(got)[:200]}")
    print(f"{len(paths) - failures}/{len(paths)} files match")
    return 1 if failures else 0


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    mode = ap.add_mutually_exclusive_group(required=True)
    mode.add_argument("--write", type=Path, metavar="JSON", help="write the meshio reference counts")
    mode.add_argument("--check", action="store_true", help="compare `nlrom mesh info --json` with meshio")
    ap.add_argument("--nlrom", type=Path, default=DEFAULT_NLROM, help="nlrom binary (default target/release/nlrom)")
    ap.add_argument("--reference", type=Path, help="with --check: take meshio's counts from this JSON")
    ap.add_argument("--timeout", type=float, default=300.0, help="seconds per nlrom run")
    ap.add_argument("-v", "--verbose", action="store_true")
    ap.add_argument("files", nargs="*", type=Path, help="with --check: only these mesh files")
    args = ap.parse_args(argv)
    if args.write:
        if args.files:
            ap.error("--write always covers every mesh in meshes/ and meshes/formats/")
        return cmd_write(args.write)
    return cmd_check(args.nlrom, args.reference, args.files, args.timeout, args.verbose)


if __name__ == "__main__":
    sys.exit(main())
