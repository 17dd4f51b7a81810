#!/usr/bin/env python3
"""The machine-level cost of one exact single-harmonic evaluation of the microslip element.

Traces the instructions of one evaluation with its Jacobian (`contact_cost microslip REGIME`:
the element and motions of `benches/microslip.rs`, the third analytic call, from the converged
slider state) by single-stepping it in gdb, then reads that sequence two ways:

* `llvm-mca` (the scheduler model of `--mcpu`, default znver3): cycles per evaluation when
  evaluations follow each other (as in the benchmark's loop) and for one evaluation alone, and
  why dispatch stalls (the scheduler or the reorder buffer full);
* its dataflow critical path: the longest chain of dependent instructions through registers and
  stack slots (spills), each instruction taking the latency of the llvm-mca model (a load 7
  cycles, a store-to-load forwarding 2 more; the stack pointer always ready, as the core's stack
  engine keeps it), without any limit on the window: the latency no schedule can beat;
* the loads from the stack that no single store before them covers (a load spanning two stores,
  or wider than the store it reads): the core cannot forward them and waits for the stores to
  reach the cache, a stall the model does not see.

Run from the repository root after `cargo build --release --example contact_cost`:

    python3 tools/benchmarks/critical_path.py [--regime separation] [--mcpu znver3] [--chain]

Needs gdb and llvm-mca (LLVM 14 or later) on the path. The counts are those of the build in
`target/release`; the cycles are the model's. To convert measured times to cycles,

    python3 tools/benchmarks/critical_path.py --clock

measures the core's clock (needs a C compiler, `cc`): the CPU time of a chain of 4e9 dependent
integer additions, one per cycle.
"""

import argparse
import collections
import os
import re
import subprocess
import sys
import tempfile

BINARY = "target/release/examples/contact_cost"
# the function the benchmark times (its analytic and AFT paths both pass here)
ENTRY = re.compile(r"^_ZN5nlrom7contact7element11evaluate_as17h[0-9a-f]{16}E$")
LOAD = 7
STORE_FORWARD = 2

GDB_SCRIPT = r"""
import gdb, os
gdb.execute("set pagination off")
gdb.execute("set confirm off")
gdb.execute("starti")
gdb.execute("set language c")
gdb.execute("break " + os.environ["CP_SYMBOL"])
gdb.execute("continue")
for _ in range(int(os.environ["CP_SKIP"])):
    gdb.execute("continue")
ret = int(gdb.parse_and_eval("*(unsigned long *)$sp"))
sp0 = int(gdb.parse_and_eval("$sp"))
with open(os.environ["CP_OUT"], "w") as out:
    for _ in range(100000):
        pc = int(gdb.parse_and_eval("$pc"))
        if pc == ret and int(gdb.parse_and_eval("$sp")) > sp0:
            break
        out.write(gdb.execute("x/i $pc", to_string=True))
        gdb.execute("stepi", to_string=True)
gdb.execute("kill")
"""


def entry_symbol(binary):
    """The mangled name of `nlrom::contact::element::evaluate_as` in `binary`."""
    names = subprocess.run(["nm", binary], capture_output=True, text=True, check=True).stdout
    for line in names.splitlines():
        parts = line.split()
        if len(parts) == 3 and ENTRY.match(parts[2]):
            return parts[2]
    sys.exit(f"{binary}: no symbol nlrom::contact::element::evaluate_as")


def trace(binary, regime, directory):
    """The executed instructions of the third analytic evaluation, as (function, text) pairs."""
    script = os.path.join(directory, "trace.py")
    out = os.path.join(directory, "trace.txt")
    with open(script, "w") as f:
        f.write(GDB_SCRIPT)
    env = dict(os.environ, CP_SYMBOL=entry_symbol(binary), CP_SKIP="2", CP_OUT=out)
    subprocess.run(
        ["gdb", "-q", "-batch", "-x", script, "--args", binary, "microslip", regime, "3"],
        env=env, capture_output=True, text=True, check=True,
    )
    steps = []
    for line in open(out):
        m = re.match(r"=> 0x[0-9a-f]+(?: <([^>+]*)[^>]*>)?:\s+(.*)", line)
        if m:
            symbol = re.sub(r"17h[0-9a-f]{16}E$", "", m.group(1) or "?")
            steps.append((symbol, re.sub(r"\s+#.*", "", m.group(2)).strip()))
    return steps


def straight_line(steps):
    """The traced instructions without jumps, calls and returns (llvm-mca's input)."""
    keep = []
    for _, text in steps:
        op = text.split()[0]
        if op.startswith(("j", "call", "ret", "nop", "endbr", "data16", "cs")):
            continue
        keep.append(text)
    return keep


def mca(path, mcpu, iterations, *flags):
    return subprocess.run(
        ["llvm-mca", f"-mcpu={mcpu}", f"-iterations={iterations}", *flags, path],
        capture_output=True, text=True, check=True,
    ).stdout


def latencies(path, mcpu, count):
    """Each instruction's latency (cycles) in the model, from llvm-mca's instruction table."""
    text = mca(path, mcpu, 1, "-instruction-info")
    table = text[text.index("[1]    [2]"):].splitlines()[1:]
    out = []
    for line in table:
        m = re.match(r"\s*\d+\s+(\d+)\s+[\d.]+", line)
        if not m:
            break
        out.append(int(m.group(1)))
    if len(out) != count:
        sys.exit(f"llvm-mca listed {len(out)} instructions, expected {count}")
    return out


# the 64-bit register of each 8-, 16- and 32-bit name of the legacy registers
LEGACY = {
    name: full
    for full, names in {
        "rax": ("al", "ax", "eax"), "rbx": ("bl", "bx", "ebx"), "rcx": ("cl", "cx", "ecx"),
        "rdx": ("dl", "dx", "edx"), "rsi": ("sil", "si", "esi"), "rdi": ("dil", "di", "edi"),
        "rbp": ("bpl", "bp", "ebp"), "rsp": ("spl", "sp", "esp"),
    }.items()
    for name in names
}


def register(name):
    """The architectural register a (sub)register name belongs to."""
    r = name.lstrip("%")
    if r.startswith(("xmm", "ymm", "zmm")):
        return "v" + re.sub(r"\D", "", r)
    if r in LEGACY:
        return LEGACY[r]
    m = re.match(r"r(\d+)[dwb]?$", r)
    return "r" + m.group(1) if m else r


def operands(text):
    parts = text.split(None, 1)
    if len(parts) == 1:
        return parts[0], []
    ops, depth, cur = [], 0, ""
    for ch in parts[1]:
        depth += (ch == "(") - (ch == ")")
        if ch == "," and depth == 0:
            ops.append(cur.strip())
            cur = ""
        else:
            cur += ch
    ops.append(cur.strip())
    return parts[0], ops


def registers_in(operand):
    return [register(r) for r in re.findall(r"%\w+", operand)]


# destinations written without reading them (the rest, two-operand SSE arithmetic, read them)
PURE_WRITE = ("mov", "lea", "cvt", "pshufd", "set", "vmov")
COMPARE = ("cmp", "ucomis", "comis", "test", "bt")
VECTOR_COMPARE = re.compile(r"^cmp(n?(lt|le|eq|ord|unord))[sp]d$")


def critical_path(lines, lat):
    """The longest dependency chain of the sequence: (length in cycles, chain indices)."""
    ready = {}
    stack = {}
    rsp = 0
    finish, pred = [0] * len(lines), [None] * len(lines)
    for i, text in enumerate(lines):
        op, ops = operands(text)
        reads, writes, load_from, store_to = [], [], None, None
        dst, srcs = (ops[-1], ops[:-1]) if ops else (None, [])
        for o in srcs:
            reads += registers_in(o)
            if "(" in o:
                load_from = o
        zero_idiom = len(ops) == 2 and ops[0] == ops[1] and op in (
            "xorpd", "xorps", "pxor", "xorl", "xorq", "subl")
        if op.startswith("push"):
            reads += registers_in(ops[0]) + ["rsp"]
            writes = ["rsp"]
            store_to = f"{rsp - 8}"
            rsp -= 8
        elif op.startswith("pop"):
            reads.append("rsp")
            writes = [register(ops[0]), "rsp"]
            load_from = f"{rsp}"
            rsp += 8
        elif op.startswith(COMPARE) and not VECTOR_COMPARE.match(op):
            reads += registers_in(dst)
            if "(" in dst:
                load_from = dst
            writes = ["flags"]
        elif dst is not None:
            if "(" in dst:
                store_to = dst
                reads += registers_in(dst)
            else:
                merge = op == "movsd" and len(ops) == 2 and ops[0].startswith("%")
                pure = op.startswith(PURE_WRITE) and not merge
                three_operand = op.startswith("v") and len(ops) == 3 and "fm" not in op
                if not (pure or three_operand) or op.startswith("sqrt"):
                    reads += registers_in(dst)
                writes = registers_in(dst)
                if op.startswith(("set", "cmov", "adc", "sbb")):
                    reads.append("flags")
        if op in ("sub", "subq", "add", "addq") and ops[-1] == "%rsp" and ops[0].startswith("$"):
            rsp += int(ops[0][1:], 0) * (1 if op.startswith("add") else -1)
        if zero_idiom:
            reads = []
        # the stack engine keeps the stack pointer ready: no chain through push, pop and rsp
        reads = [r for r in reads if r != "rsp"]
        writes = [w for w in writes if w != "rsp"]
        address = set(registers_in(load_from)) if load_from and "(" in load_from else set()
        latency = lat[i] - LOAD if load_from and lat[i] > LOAD else lat[i]
        start, before = 0, None
        for r in reads:
            t, j = ready.get(r, (0, None))
            t += LOAD if r in address else 0
            if t > start:
                start, before = t, j
        key = slot(load_from, rsp)
        if key in stack and stack[key][0] + STORE_FORWARD + LOAD > start:
            start, before = stack[key][0] + STORE_FORWARD + LOAD, stack[key][1]
        finish[i], pred[i] = start + latency, before
        for w in writes:
            ready[w] = (finish[i], i)
        key = slot(store_to, rsp)
        if key is not None:
            stack[key] = (finish[i], i)
    end = max(range(len(lines)), key=lambda k: finish[k])
    chain, k = [], end
    while k is not None:
        chain.append(k)
        k = pred[k]
    return finish[end], chain[::-1], finish


def slot(operand, rsp):
    """A stack slot's address relative to the entry's stack pointer, or None."""
    if operand is None:
        return None
    if re.fullmatch(r"-?\d+", operand):
        return int(operand)
    m = re.fullmatch(r"(-?(?:0x)?[0-9a-f]*)\(%rsp\)", operand)
    if not m:
        return None
    return rsp + (int(m.group(1), 0) if m.group(1) else 0)


def access_width(op, ops):
    """Bytes a memory operand of the instruction `op` covers."""
    if op in ("movsd", "movq", "movlpd", "movhpd", "vmovsd", "vmovq"):
        return 8
    if op.startswith(("movap", "movup", "movdq")) or op.endswith(("pd", "ps")):
        return 16
    if op.endswith("sd"):
        return 8
    if op.endswith("ss"):
        return 4
    registers = [o for o in ops if o.startswith("%")]
    if registers and registers[0].startswith("%xmm"):
        return 16
    if registers and (registers[0].startswith("%e") or registers[0].endswith("d")):
        return 4
    return 8


def unforwarded_loads(steps):
    """The loads from the stack that no single earlier store covers: (index, load, stores)."""
    rsp, stack_registers, stores, found = 0, {}, [], []

    def address(operand):
        m = re.fullmatch(r"(-?(?:0x)?[0-9a-f]*)\((%\w+)\)", operand)
        if not m:
            return None
        offset = int(m.group(1), 0) if m.group(1) else 0
        if m.group(2) == "%rsp":
            return rsp + offset
        base = stack_registers.get(m.group(2))
        return None if base is None else base + offset

    for i, (_, text) in enumerate(steps):
        op, ops = operands(text)
        if op.startswith(("push", "call")):
            rsp -= 8
            stores.append((rsp, rsp + 8, text))
            continue
        if op.startswith(("pop", "ret")):
            rsp += 8
            continue
        if op in ("sub", "subq", "add", "addq") and ops[-1] == "%rsp" and ops[0].startswith("$"):
            rsp += int(ops[0][1:], 0) * (1 if op.startswith("add") else -1)
            continue
        if op.startswith("lea") and len(ops) == 2:
            start = address(ops[0])
            if start is None:
                stack_registers.pop(ops[1], None)
            else:
                stack_registers[ops[1]] = start
            continue
        if ops and ops[-1] in stack_registers:
            del stack_registers[ops[-1]]
        memory = [o for o in ops if "(" in o]
        start = address(memory[0]) if memory else None
        if start is None:
            continue
        end = start + access_width(op, ops)
        if ops[-1] == memory[0] and not op.startswith(COMPARE):
            stores.append((start, end, text))
            continue
        needed, covering = set(range(start, end)), []
        for s_start, s_end, s_text in reversed(stores):
            overlap = needed & set(range(s_start, s_end))
            if overlap:
                covering.append((s_start, s_end, s_text))
                needed -= overlap
            if not needed:
                break
        whole = len(covering) == 1 and covering[0][0] <= start and covering[0][1] >= end
        if covering and not whole:
            found.append((i, text, [c[2] for c in covering]))
    return found


def stalls(text):
    """llvm-mca's dispatch stall lines (name: cycles and share)."""
    out = []
    block = text[text.index("Dynamic Dispatch Stall Cycles"):].splitlines()[1:8]
    for line in block:
        m = re.match(r"(\w+)\s+-\s+([^:]+):\s+(\d+)(?:\s+\(([\d.]+)%\))?", line)
        if m and int(m.group(3)) > 0:
            out.append(f"{m.group(2).strip()}: {m.group(4)} %")
    return out


CLOCK_C = r"""
#include <stdio.h>
#include <time.h>
int main(void) {
    const long n = 4000000000L;
    long x = 0;
    struct timespec a, b;
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &a);
    for (long i = 0; i < n; i += 8) {
        /* eight dependent additions per round: one cycle each; the loop's own increment and
           branch run beside them */
        __asm__ volatile("add $1, %0\n\tadd $1, %0\n\tadd $1, %0\n\tadd $1, %0\n\t"
                         "add $1, %0\n\tadd $1, %0\n\tadd $1, %0\n\tadd $1, %0"
                         : "+r"(x));
    }
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &b);
    double s = (b.tv_sec - a.tv_sec) + 1e-9 * (b.tv_nsec - a.tv_nsec);
    printf("%ld additions in %.3f s of CPU: %.2f GHz\n", x, s, x / s * 1e-9);
    return 0;
}
"""


def clock():
    """Compiles and runs the chain of dependent additions of CLOCK_C; prints the clock."""
    with tempfile.TemporaryDirectory() as directory:
        source = os.path.join(directory, "clock.c")
        binary = os.path.join(directory, "clock")
        with open(source, "w") as f:
            f.write(CLOCK_C)
        subprocess.run(["cc", "-O1", "-o", binary, source], check=True)
        subprocess.run([binary], check=True)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--regime", default="separation",
                        choices=["stick", "jenkins", "stickslip", "separation"])
    parser.add_argument("--binary", default=BINARY)
    parser.add_argument("--mcpu", default="znver3")
    parser.add_argument("--chain", action="store_true", help="print the critical chain")
    parser.add_argument("--clock", action="store_true",
                        help="measure the core's clock (a chain of dependent additions) and exit")
    args = parser.parse_args()
    if args.clock:
        clock()
        return
    with tempfile.TemporaryDirectory() as directory:
        steps = trace(args.binary, args.regime, directory)
        lines = straight_line(steps)
        path = os.path.join(directory, "trace.s")
        with open(path, "w") as f:
            f.write("\n".join(lines) + "\n")
        repeated = mca(path, args.mcpu, 100, "-dispatch-stats")
        alone = mca(path, args.mcpu, 1)
        lat = latencies(path, args.mcpu, len(lines))
    cycles = int(re.search(r"Total Cycles:\s+(\d+)", repeated).group(1)) / 100
    single = int(re.search(r"Total Cycles:\s+(\d+)", alone).group(1))
    length, chain, _ = critical_path(lines, lat)
    by_function = collections.Counter(symbol for symbol, _ in steps)
    kinds = collections.Counter()
    for text in lines:
        op, ops = operands(text)
        if op.startswith("mov") and len(ops) == 2 and all(o.startswith("%xmm") for o in ops):
            kinds["register copies"] += 1
        elif any("(%rsp)" in o for o in ops):
            kinds["stack operands (spills, reloads)"] += 1
        elif op in ("unpcklpd", "unpckhpd", "shufpd", "pshufd", "movlhps", "movhlps"):
            kinds["shuffles"] += 1
        elif op.startswith(("sqrt", "div")):
            kinds["square roots and divisions"] += 1
    print(f"{args.regime}: {len(steps)} instructions executed ({len(lines)} without branches)")
    for symbol, count in by_function.most_common():
        print(f"  {count:5d}  {symbol}")
    for kind, count in kinds.most_common():
        print(f"  of which {kind}: {count}")
    print(f"llvm-mca -mcpu={args.mcpu}: {cycles:.0f} cycles per evaluation in a loop, "
          f"{single} for one alone")
    print("  dispatch stalls: " + "; ".join(stalls(repeated)))
    print(f"dataflow critical path: {length} cycles, {len(chain)} instructions")
    unforwarded = unforwarded_loads(steps)
    print(f"loads from the stack no single store covers (not forwarded): {len(unforwarded)}")
    for i, text, covering in unforwarded:
        print(f"  {i:5d}  {text}  <- " + "; ".join(covering))
    if args.chain:
        _, _, finish = critical_path(lines, lat)
        for k in chain:
            print(f"  {finish[k]:4d}  {lines[k]}")


if __name__ == "__main__":
    main()
