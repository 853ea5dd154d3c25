"""What an XDMF reader must deliver for a run, from result.h5, run.json and the scene (shared by
read_xdmf_meshio.py and read_xdmf_paraview.py)."""
import json
import os

import h5py
import numpy as np


class Expected:
    def __init__(self, run, end_time, rate):
        self.h5 = h5py.File(os.path.join(run, "result.h5"), "r")
        self.scene = json.loads(self.h5.attrs["scene_json"])
        self.problems = []
        self.particles = json.load(open(os.path.join(run, "run.json")))["cost"]["particles"]
        # The particles the water boxes seed (solver/seeding.h: round(L / spacing) per axis, dx / ppc^(1/3) apart).
        s = self.scene["solver"]
        spacing = s["dx"] / round(s["ppc"] ** (1 / 3))
        seeded = sum(int(np.prod([max(1, round((h - l) / spacing)) for l, h in zip(w["lo"], w["hi"])]))
                     for w in self.scene["water"])
        if self.particles != seeded:
            self.problems.append(f"run.json has {self.particles} particles, the scene's water boxes seed {seeded}")
        self.snapshot_steps = int(np.floor(end_time * rate + 1e-9)) + 1  # t = 0, 1/rate, ..., and the end
        self.snapshots = [self.h5["snapshots"][k] for k in sorted(self.h5["snapshots"])]
        self.snapshot_times = [float(g.attrs["time"]) for g in self.snapshots]
        self.bodies = self.scene["debris"]["bodies"]
        self.debris_times = [float(t) for t in self.h5[f"/debris/{self.bodies[0]['name']}/resampled/time"][()]]

    def corner_error(self, b, t, corners):
        """Largest distance (m) from a corner read to the nearest corner of body b's box at its pose at t."""
        rec = self.h5[f"/debris/{self.bodies[b]['name']}/resampled"]
        i = int(np.argmin(np.abs(rec["time"][()] - t)))
        if abs(rec["time"][i] - t) > 1e-9:
            self.problems.append(f"debris: t = {t} is no resampled time of {self.bodies[b]['name']}")
        w, x, y, z = rec["orientation"][i]
        r = np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                      [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                      [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]])
        signs = np.array([[sx, sy, sz] for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)], dtype=float)
        expect = rec["position"][i] + (signs * 0.5 * np.array(self.bodies[b]["size"], dtype=float)) @ r.T
        corners = np.asarray(corners, dtype=float)
        return float(np.max(np.min(np.linalg.norm(corners[:, None, :] - expect[None, :, :], axis=2), axis=1)))

    # float32 coordinates of points within 2 m of the origin are exact to 1e-6 m; 1e-5 m leaves margin.
    corner_tolerance_m = 1e-5
