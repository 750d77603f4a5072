#!/usr/bin/env python3
"""Read every .vtu of a tricontact result folder with meshio and check it.

Usage: python3 scripts/check_vtu.py RESULTS_DIR [MODEL_STEM]
Needs `pip install meshio`. Checks, per file: the grid parses, has points and
volume cells, carries the point fields displacement/reaction/stress/von_mises
and cell fields stress/von_mises with the right shapes and finite values; and
that the .pvd lists files that exist. Exit code 0 when all checks pass.
"""
import glob
import os
import sys
import xml.etree.ElementTree as ET

import meshio
import numpy as np


def main() -> int:
    folder = sys.argv[1] if len(sys.argv) > 1 else "results"
    files = sorted(glob.glob(os.path.join(folder, "*.vtu")))
    if not files:
        print(f"no .vtu files in {folder}")
        return 1
    ok = True
    for f in files:
        m = meshio.read(f)
        n = len(m.points)
        ncell = sum(len(c.data) for c in m.cells)
        problems = []
        for name, comps in [("displacement", 3), ("reaction", 3), ("stress", 6), ("von_mises", 1)]:
            a = m.point_data.get(name)
            if a is None:
                problems.append(f"missing point field {name}")
                continue
            a = np.asarray(a).reshape(n, -1)
            if a.shape[1] != comps or not np.all(np.isfinite(a)):
                problems.append(f"bad point field {name} {a.shape}")
        for name in ["stress", "von_mises"]:
            blocks = m.cell_data.get(name)
            if blocks is None:
                problems.append(f"missing cell field {name}")
                continue
            total = sum(len(b) for b in blocks)
            if total != ncell:
                problems.append(f"cell field {name} has {total} values for {ncell} cells")
        types = sorted({c.type for c in m.cells})
        umax = np.abs(np.asarray(m.point_data["displacement"])).max() if "displacement" in m.point_data else float("nan")
        status = "OK" if not problems else "FAIL: " + "; ".join(problems)
        print(f"{os.path.basename(f)}: {n} points, {ncell} cells {types}, max |u_i| = {umax:.6g}: {status}")
        ok = ok and not problems
    for pvd in glob.glob(os.path.join(folder, "*.pvd")):
        entries = ET.parse(pvd).getroot().findall(".//DataSet")
        missing = [e.get("file") for e in entries if not os.path.exists(os.path.join(folder, e.get("file")))]
        print(f"{os.path.basename(pvd)}: {len(entries)} time steps, missing files: {missing or 'none'}")
        ok = ok and not missing
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
