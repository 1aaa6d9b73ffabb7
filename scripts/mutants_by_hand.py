#!/usr/bin/env python3
"""Apply chosen mutants by hand to the warm build and run one test target against each.

    python3 scripts/mutants_by_hand.py      # the host-physics list below (docs/mutants.md)

cargo-mutants builds every mutant in a fresh copy of the workspace (minutes each on a
shared 2-core machine); for a short list of known survivors it is quicker to edit the
source in place, run `cargo test -p dexter-sim --test host_physics_by_hand`, and restore
the file with `git checkout` (always, also when interrupted). Each entry is (file, line,
column, operator, replacement) as cargo-mutants names it. Prints CAUGHT (the test failed),
MISSED or UNVIABLE per mutant; exit 1 if any is missed. Run it on a clean work tree.
"""
import subprocess, sys

TEST = ["cargo", "test", "-q", "-p", "dexter-sim", "--test", "host_physics_by_hand"]
muts = [
 ("host-sim/src/engine/roots.rs",39,43,"&&","||"),
 ("host-sim/src/engine/roots.rs",39,79,"||","&&"),
 ("host-sim/src/engine/roots.rs",43,15,"<","=="),
 ("host-sim/src/engine/roots.rs",46,29,"==","!="),
 ("host-sim/src/engine/roots.rs",74,20,"*","/"),
 ("host-sim/src/engine/roots.rs",74,20,"*","+"),
 ("host-sim/src/engine/roots.rs",107,14,">",">="),
 ("host-sim/src/model/line.rs",173,33,"+=","-="),
 ("host-sim/src/model/line.rs",177,33,"+=","*="),
 ("host-sim/src/model/line.rs",152,33,"+=","-="),
 ("host-sim/src/engine/flight.rs",103,32,"-","+"),
 ("host-sim/src/engine/flight.rs",104,36,"-","+"),
]
missed = 0
for f,l,c,a,b in muts:
    src=open(f).read().split("\n")
    line=src[l-1]
    i=c-1
    if line[i:i+len(a)]!=a:
        print(f"SKIP {f}:{l}:{c} '{line[i:i+len(a)]}' != '{a}'", flush=True); continue
    src[l-1]=line[:i]+b+line[i+len(a):]
    open(f,"w").write("\n".join(src))
    try:
        r=subprocess.run(TEST,capture_output=True,text=True,timeout=900)
        out=r.stdout+r.stderr
        status="CAUGHT" if r.returncode!=0 else "MISSED"
        if "error[" in out: status="UNVIABLE"
        failed=[x.split()[1] for x in out.splitlines() if x.startswith("---- ")]
        missed += status == "MISSED"
        print(f"{status} {f}:{l}:{c}: {a} -> {b}  {failed}", flush=True)
    finally:
        subprocess.run(["git","checkout","-q",f])
sys.exit(1 if missed else 0)
