#!/usr/bin/python3
"""Instructions (and simulated last-level misses) per vertex-step of gradel-bench, from callgrind.

Runs one gradel-bench configuration under `valgrind --tool=callgrind`, collecting only inside
World::step (scene building, metrics and frames excluded), with one repetition of one timed step
(--reps 1 --min-time 0.001: a step under valgrind always exceeds the calibration's 0.25 ms), and
prints  set,n,vertices,steps,instructions_per_vertex_step[,ll_misses_per_vertex_step],state_hash.

  bench/callgrind_step.py [--cache] [--bench build/gradel-bench] -- --sets paper --sizes 32 ...

--cache simulates the caches (32 KiB L1, 16 MiB 16-way last level, as in docs/speed.md; --ll-mib
sets the last level's size, 32 for this VM's L3) and reports last-level data misses (DLmr + DLmw)
per vertex-step. Threads must be 1. The last column
is the row's state hash: compare it with a run outside valgrind (see patch_vmovq below).
"""
import argparse
import os
import re
import subprocess
import sys
import tempfile


def parse(path):
    """Totals of the collected events and the number of calls of gradel::World::step()."""
    names, events, totals, calls = {}, [], None, 0
    pending = False
    with open(path) as f:
        for line in f:
            if line.startswith("events:"):
                events = line.split()[1:]
            elif line.startswith("summary:") or line.startswith("totals:"):
                totals = [int(v) for v in line.split()[1:]]
            elif line.startswith("cfn="):
                m = re.match(r"cfn=\((\d+)\)(?: (.*))?", line.strip())
                if m.group(2):
                    names[m.group(1)] = m.group(2)
                pending = names.get(m.group(1)) == "gradel::World::step()"
            elif line.startswith("calls=") and pending:
                calls += int(line.split("=")[1].split()[0])
                pending = False
            elif line.startswith("fn="):
                m = re.match(r"fn=\((\d+)\)(?: (.*))?", line.strip())
                if m and m.group(2):
                    names[m.group(1)] = m.group(2)
    return dict(zip(events, totals)), calls


def patch_vmovq(src, dst):
    """valgrind 3.19 cannot decode the register form of the VEX vmovq store (c5 X9 d6 /r, mod 11),
    which g++ 12 emits at -march=x86-64-v3. Copy the binary with each one rewritten as the vmovapd
    store of the same length (c5 X9 29 /r): the destination's upper half then holds the source's
    instead of zero, which scalar code does not read (the state hash tells)."""
    dis = subprocess.run(["objdump", "-d", "-w", src], capture_output=True, text=True).stdout
    data = bytearray(open(src, "rb").read())
    for line in dis.splitlines():
        m = re.match(r"\s*([0-9a-f]+):\s+c5 [0-9a-f]9 d6 [c-f][0-9a-f]\s+vmovq", line)
        if m:  # text is mapped at file offset == address in these binaries: check the bytes
            a = int(m.group(1), 16)
            if data[a] != 0xC5 or data[a + 2] != 0xD6:
                sys.exit(f"patch_vmovq: unexpected bytes at {a:#x}")
            data[a + 2] = 0x29
    with open(dst, "wb") as f:
        f.write(data)
    os.chmod(dst, 0o755)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--cache", action="store_true")
    ap.add_argument("--ll-mib", type=int, default=16, help="last-level cache size of the model [MiB] (16-way)")
    ap.add_argument("--bench", default="build/gradel-bench")
    ap.add_argument("rest", nargs=argparse.REMAINDER)
    a = ap.parse_args()
    rest = [x for x in a.rest if x != "--"]
    with tempfile.TemporaryDirectory() as tmp:
        out = os.path.join(tmp, "cg.out")
        bench = os.path.join(tmp, "bench")
        patch_vmovq(a.bench, bench)
        cmd = ["valgrind", "--tool=callgrind", f"--callgrind-out-file={out}",
               "--toggle-collect=gradel::World::step()"]
        if a.cache:
            cmd += ["--cache-sim=yes", "--I1=32768,8,64", "--D1=32768,8,64", f"--LL={a.ll_mib << 20},16,64"]
        cmd += [bench, "--threads", "1", "--reps", "1", "--min-time", "0.001"] + rest
        r = subprocess.run(cmd, capture_output=True, text=True)
        if r.returncode != 0:
            sys.exit(r.stderr)
        rows = [l for l in r.stdout.splitlines() if l and not l.startswith("set,") and not l.startswith("#")]
        ev, calls = parse(out)
    for row in rows[:1]:
        c = row.split(",")
        vertices = int(c[8])
        per = ev["Ir"] / (calls * vertices)
        line = f"{c[0]},{c[2]},{vertices},{calls},{per:.1f}"
        if a.cache:
            line += f",{(ev.get('DLmr', 0) + ev.get('DLmw', 0)) / (calls * vertices):.3f}"
        print(line + "," + c[16])
    if len(rows) != 1:
        print(f"warning: {len(rows)} rows; counts are of all of them together", file=sys.stderr)


if __name__ == "__main__":
    main()
