#!/usr/bin/python3
"""Opens a run's result.xmf with meshio's XDMF reader (Debian python3-meshio) and checks what it reads against
result.h5 and the scene (xdmf_expect.py): the particle count, positions and snapshot times, and the debris
boxes' corners against the recorded pose (position, orientation quaternion) and the scene's box size.

    read_xdmf_meshio.py RUN_DIR END_TIME_S SNAPSHOT_RATE_HZ

meshio reads XDMF 2 one Uniform grid per file (no temporal collections, no <Time>), so each step of each
temporal collection is handed to it as a one-grid document beside result.h5: meshio resolves the step's
DataItems (HDF paths, XML connectivity), its topology and attributes itself. A Polyvertex topology gets its
implied connectivity (point i is vertex i) written out, which meshio needs and XDMF lets the writer omit.
The collections, their order and their times are read from the same XML.
"""
import copy
import os
import sys
import xml.etree.ElementTree as ET

import meshio
import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from xdmf_expect import Expected  # noqa: E402

run = sys.argv[1]
ex = Expected(run, float(sys.argv[2]), float(sys.argv[3]))
problems = ex.problems
root = ET.parse(os.path.join(run, "result.xmf")).getroot()


def read_step(grid, k):
    """The step's Grid as a one-grid XDMF 2 file beside result.h5, read by meshio."""
    g = copy.deepcopy(grid)
    for t in g.findall("Time"):
        g.remove(t)
    topo = g.find("Topology")
    if topo.get("TopologyType") == "Polyvertex" and topo.find("DataItem") is None:
        n = int(topo.get("NumberOfElements"))
        item = ET.SubElement(topo, "DataItem", Dimensions=f"{n} 1", NumberType="Int", Format="XML")
        item.text = " ".join(map(str, range(n)))
    doc = ET.Element("Xdmf", Version="2.0")
    ET.SubElement(doc, "Domain").append(g)
    path = os.path.join(run, f"step_{k}.xmf")
    ET.ElementTree(doc).write(path)
    try:
        return meshio.read(path, file_format="xdmf")
    finally:
        os.remove(path)


collections = {c.get("Name"): c for c in root.find("Domain").findall("Grid")}

steps = collections["particles"].findall("Grid")
times = [float(g.find("Time").get("Value")) for g in steps]
if len(steps) != ex.snapshot_steps:
    problems.append(f"particles: {len(steps)} steps, expected {ex.snapshot_steps}")
if not np.allclose(times, ex.snapshot_times, rtol=0, atol=1e-12):
    problems.append(f"particles: XDMF times {times}, result.h5 {ex.snapshot_times}")
for k, g in enumerate(steps):
    m = read_step(g, k)
    snap = ex.snapshots[min(k, len(ex.snapshots) - 1)]
    if m.points.shape != (ex.particles, 3):
        problems.append(f"particles step {k}: meshio read {m.points.shape} points, the run has {ex.particles}")
    elif not np.array_equal(m.points, snap["xyz"][()]):
        problems.append(f"particles step {k}: the points meshio read are not snapshot {k}'s positions")
    if [c.type for c in m.cells] != ["vertex"] or len(m.cells[0].data) != ex.particles:
        problems.append(f"particles step {k}: cells {[(c.type, len(c.data)) for c in m.cells]}")
    for name in ("pressure", "velocity"):
        v = m.point_data.get(name)
        if v is None or not np.array_equal(v, snap[name][()]):
            problems.append(f"particles step {k}: point data {name} is not snapshot {k}'s")
print(f"meshio: particles: {len(steps)} steps at t = {', '.join(f'{t:.3f}' for t in times)} s, "
      f"{ex.particles} points each")

steps = collections["debris"].findall("Grid")
if len(steps) != len(ex.debris_times):
    problems.append(f"debris: {len(steps)} steps, result.h5 has {len(ex.debris_times)} resampled times")
worst = 0.0
for k, g in enumerate(steps):
    t = float(g.find("Time").get("Value"))
    m = read_step(g, f"d{k}")
    hexes = [c for c in m.cells if c.type == "hexahedron"]
    if len(hexes) != 1 or len(hexes[0].data) != len(ex.bodies):
        problems.append(f"debris step {k}: cells {[(c.type, len(c.data)) for c in m.cells]}, {len(ex.bodies)} bodies")
        continue
    for b, cell in enumerate(hexes[0].data):
        d = ex.corner_error(b, t, m.points[cell])
        worst = max(worst, d)
        if d > ex.corner_tolerance_m:
            problems.append(f"debris step {k} body {b}: a corner {d:.2e} m from the recorded pose's box")
print(f"meshio: debris: {len(steps)} steps, {len(ex.bodies)} box(es), corners within {worst:.1e} m of the recorded pose")
if problems:
    print("\n".join(problems[:20]))
    sys.exit(1)
