#!/usr/bin/env python3
"""Fills the seed corpus of the `msh` fuzz target (fuzz/corpus/msh/, git-ignored).

Copies the bundled meshes of at most 2 x max_len bytes (128 KiB by default; libFuzzer truncates
seeds to -max_len, 64 KiB here, so the largest ones become truncated-file seeds) and writes a few
tiny hand-made meshes — one tetrahedron, a face of it, a point, a periodic link — in every
variant the reader accepts (MSH 4.1 / 2.2, ASCII / binary little- and big-endian), so that the
fuzzer starts from small inputs that reach every section parser and `group_faces`. Also copies
the malformed files of the integration tests (tests/data/broken/*.msh).

Usage (from the repository root or from fuzz/):  python3 fuzz/make_seeds.py [max_len]
"""

import shutil
import struct
import sys
from pathlib import Path

FUZZ = Path(__file__).resolve().parent
ROOT = FUZZ.parent
OUT = FUZZ / "corpus" / "msh"
MAX_LEN = int(sys.argv[1]) if len(sys.argv) > 1 else 65536

NODES = [(1, (0.0, 0.0, 0.0)), (2, (1.0, 0.0, 0.0)), (3, (0.0, 1.0, 0.0)), (4, (0.0, 0.0, 1.0))]
NAMES = [(0, 3, "pt"), (2, 1, "face"), (3, 2, "solid")]
# (dim, entity, gmsh type, element tag, node tags)
ELEMS = [(0, 1, 15, 1, [1]), (2, 5, 2, 2, [1, 2, 3]), (3, 7, 4, 3, [1, 2, 3, 4])]
AFFINE = [1.0, 0, 0, 0, 0, 1.0, 0, 0, 0, 0, 1.0, 0, 0, 0, 0, 1.0]


def physical_names():
    s = f"$PhysicalNames\n{len(NAMES)}\n"
    s += "".join(f'{d} {t} "{n}"\n' for d, t, n in NAMES)
    return (s + "$EndPhysicalNames\n").encode()


def v41_ascii():
    s = "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n"
    out = s.encode() + physical_names()
    s = "$Entities\n1 0 1 1\n1 0 0 0 1 3\n5 0 0 0 1 1 0 1 1 0\n7 0 0 0 1 1 1 1 2 1 5\n$EndEntities\n"
    s += f"$Nodes\n1 {len(NODES)} 1 {len(NODES)}\n3 7 0 {len(NODES)}\n"
    s += "".join(f"{t}\n" for t, _ in NODES)
    s += "".join(f"{x} {y} {z}\n" for _, (x, y, z) in NODES)
    s += "$EndNodes\n"
    s += f"$Elements\n{len(ELEMS)} {len(ELEMS)} 1 {len(ELEMS)}\n"
    for d, e, ty, tag, nodes in ELEMS:
        s += f"{d} {e} {ty} 1\n{tag} {' '.join(map(str, nodes))}\n"
    s += "$EndElements\n"
    s += "$Periodic\n1\n0 1 1\n16 " + " ".join(map(str, AFFINE)) + "\n1\n1 1\n$EndPeriodic\n"
    s += "$NodeData\n1\n\"skipped\"\n$EndNodeData\n"
    return out + s.encode()


def v41_binary(e):
    i32 = lambda v: struct.pack(e + "i", v)
    u64 = lambda v: struct.pack(e + "Q", v)
    f64 = lambda *v: struct.pack(e + f"{len(v)}d", *v)
    out = b"$MeshFormat\n4.1 1 8\n" + i32(1) + b"\n$EndMeshFormat\n" + physical_names()
    out += b"$Entities\n" + u64(1) + u64(0) + u64(1) + u64(1)
    out += i32(1) + f64(0, 0, 0) + u64(1) + i32(3)
    out += i32(5) + f64(0, 0, 0, 1, 1, 0) + u64(1) + i32(1) + u64(0)
    out += i32(7) + f64(0, 0, 0, 1, 1, 1) + u64(1) + i32(2) + u64(1) + i32(5)
    out += b"\n$EndEntities\n$Nodes\n" + u64(1) + u64(len(NODES)) + u64(1) + u64(len(NODES))
    out += i32(3) + i32(7) + i32(0) + u64(len(NODES))
    out += b"".join(u64(t) for t, _ in NODES) + b"".join(f64(*p) for _, p in NODES)
    out += b"\n$EndNodes\n$Elements\n" + u64(len(ELEMS)) + u64(len(ELEMS)) + u64(1) + u64(len(ELEMS))
    for d, ent, ty, tag, nodes in ELEMS:
        out += i32(d) + i32(ent) + i32(ty) + u64(1) + u64(tag) + b"".join(u64(n) for n in nodes)
    out += b"\n$EndElements\n$Periodic\n" + u64(1) + i32(0) + i32(1) + i32(1)
    out += u64(16) + f64(*AFFINE) + u64(1) + u64(1) + u64(1)
    return out + b"\n$EndPeriodic\n"


def v22_elements_ascii():
    s = f"$Elements\n{len(ELEMS)}\n"
    for d, ent, ty, tag, nodes in ELEMS:
        phys = {0: 3, 2: 1, 3: 2}[d]
        s += f"{tag} {ty} 2 {phys} {ent} {' '.join(map(str, nodes))}\n"
    return s + "$EndElements\n"


def v22_ascii():
    out = b"$MeshFormat\n2.2 0 8\n$EndMeshFormat\n" + physical_names()
    s = f"$Nodes\n{len(NODES)}\n" + "".join(f"{t} {x} {y} {z}\n" for t, (x, y, z) in NODES)
    s += "$EndNodes\n" + v22_elements_ascii()
    s += "$Periodic\n1\n0 1 1\nAffine " + " ".join(map(str, AFFINE)) + "\n1\n1 1\n$EndPeriodic\n"
    return out + s.encode()


def v22_binary(e):
    i32 = lambda *v: struct.pack(e + f"{len(v)}i", *v)
    out = b"$MeshFormat\n2.2 1 8\n" + i32(1) + b"\n$EndMeshFormat\n" + physical_names()
    out += f"$Nodes\n{len(NODES)}\n".encode()
    out += b"".join(i32(t) + struct.pack(e + "3d", *p) for t, p in NODES)
    out += f"\n$EndNodes\n$Elements\n{len(ELEMS)}\n".encode()
    for d, ent, ty, tag, nodes in ELEMS:
        phys = {0: 3, 2: 1, 3: 2}[d]
        out += i32(ty, 1, 2) + i32(tag, phys, ent, *nodes)
    out += b"\n$EndElements\n"
    # MSH 2.2 writes $Periodic in ASCII also in binary files.
    out += b"$Periodic\n1\n0 1 1\n1\n1 1\n$EndPeriodic\n"
    return out


def main():
    OUT.mkdir(parents=True, exist_ok=True)
    copied = 0
    for p in sorted(list((ROOT / "meshes").glob("*.msh")) + list((ROOT / "meshes" / "formats").glob("*.msh"))):
        if p.stat().st_size <= 2 * MAX_LEN:  # libFuzzer truncates longer seeds to -max_len
            name = p.name if p.parent.name == "meshes" else "formats-" + p.name
            shutil.copyfile(p, OUT / name)
            copied += 1
    # The hand-made malformed files of the integration tests (tests/msh_malformed.rs).
    broken = sorted((ROOT / "tests" / "data" / "broken").glob("*.msh"))
    for p in broken:
        shutil.copyfile(p, OUT / ("broken-" + p.name))
    tiny = {
        "tiny.v41-ascii.msh": v41_ascii(),
        "tiny.v41-binary-le.msh": v41_binary("<"),
        "tiny.v41-binary-be.msh": v41_binary(">"),
        "tiny.v22-ascii.msh": v22_ascii(),
        "tiny.v22-binary-le.msh": v22_binary("<"),
        "tiny.v22-binary-be.msh": v22_binary(">"),
    }
    for name, data in tiny.items():
        (OUT / name).write_bytes(data)
    print(f"{OUT}: {copied} bundled meshes (<= {2 * MAX_LEN} bytes), {len(broken)} malformed test files, {len(tiny)} tiny seeds")


if __name__ == "__main__":
    main()
