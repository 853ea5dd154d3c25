"""Opens a run's result.xmf with ParaView's own XDMF reader (run by pvpython) and checks what it reads against
result.h5 and the scene (xdmf_expect.py): the steps' times, the particle count and positions at every
snapshot, and the debris boxes' corners at the recorded pose.

    pvpython read_xdmf_paraview.py RUN_DIR END_TIME_S SNAPSHOT_RATE_HZ
"""
import os
import sys

import numpy as np
from paraview import servermanager
from paraview.simple import UpdatePipeline, XDMFReader
from vtk.util.numpy_support import vtk_to_numpy

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from xdmf_expect import Expected  # noqa: E402

run = sys.argv[1]
ex = Expected(run, float(sys.argv[2]), float(sys.argv[3]))
problems = ex.problems
reader = XDMFReader(FileNames=[os.path.join(run, "result.xmf")])
times = sorted(reader.TimestepValues)  # ParaView lists each collection's steps in turn
want = sorted(set(ex.snapshot_times) | set(ex.debris_times))
if len(times) != len(want) or not np.allclose(times, want, rtol=0, atol=1e-12):
    problems.append(f"ParaView's steps {times}, result.h5's snapshot and debris times {want}")


def blocks(data):
    """The leaf datasets of the reader's output at one time, by block name."""
    out = {}
    it = data.NewIterator()
    it.InitTraversal()
    while not it.IsDoneWithTraversal():
        name = it.GetCurrentMetaData().Get(data.NAME()) if it.GetCurrentMetaData() else str(len(out))
        out[name] = it.GetCurrentDataObject()
        it.GoToNextItem()
    return out


worst, seen_particles, seen_debris = 0.0, set(), set()  # the snapshot and debris steps shown
for t in times:
    UpdatePipeline(time=t, proxy=reader)
    data = servermanager.Fetch(reader)
    for name, ds in blocks(data).items():
        pts = vtk_to_numpy(ds.GetPoints().GetData())
        if ds.GetNumberOfCells() == ds.GetNumberOfPoints() == ex.particles:  # the particles
            k = int(np.argmin(np.abs(np.array(ex.snapshot_times) - t)))
            if abs(ex.snapshot_times[k] - t) < 1e-12:
                seen_particles.add(k)
                if not np.array_equal(pts, ex.snapshots[k]["xyz"][()]):
                    problems.append(f"t = {t}: ParaView's particle positions are not snapshot {k}'s")
        elif ds.GetNumberOfCells() == len(ex.bodies):  # the debris hexahedra
            k = int(np.argmin(np.abs(np.array(ex.debris_times) - t)))
            if abs(ex.debris_times[k] - t) < 1e-12:
                seen_debris.add(k)
                for b in range(len(ex.bodies)):
                    ids = ds.GetCell(b).GetPointIds()
                    corners = pts[[ids.GetId(i) for i in range(ids.GetNumberOfIds())]]
                    d = ex.corner_error(b, t, corners)
                    worst = max(worst, d)
                    if d > ex.corner_tolerance_m:
                        problems.append(f"t = {t} body {b}: a corner {d:.2e} m from the recorded pose's box")
        else:
            problems.append(f"t = {t}: block {name} with {ds.GetNumberOfPoints()} points, {ds.GetNumberOfCells()} cells")
if len(seen_particles) != ex.snapshot_steps:
    problems.append(f"ParaView showed {len(seen_particles)} particle snapshots, expected {ex.snapshot_steps}")
if len(seen_debris) != len(ex.debris_times):
    problems.append(f"ParaView showed debris at {len(seen_debris)} of the {len(ex.debris_times)} resampled times")
print(f"pvpython: {len(times)} steps; {len(seen_particles)} particle snapshots of {ex.particles} points; "
      f"debris at {len(seen_debris)} times, corners within {worst:.1e} m of the recorded pose")
if problems:
    print("\n".join(problems[:20]))
    sys.exit(1)
