"""check_xdmf.py RUN.h5 XDMF PNG -- run under ParaView's own pvbatch
(paraview.bats): ParaView's XDMF Reader opens pd-dump2vtk --xdmf's
description XDMF of RUN.h5 (the data read in place, from RUN.h5) and finds
  - the complete frames' times as its time steps;
  - per time, one point per particle at x + u, u the frame's displacement,
    bit for bit, and one vertex cell a point;
  - the point arrays displacement, velocity, damage, material and id (and
    strain_energy_density, von_mises, stress and damage_run where the
    frame holds them), each equal to the run file's dataset bit for bit
    and nothing else.
Then it draws the last frame coloured by damage into PNG and reads it back:
the middle is not the background.  Prints "ok NFRAMES".
"""
import sys

import h5py
import numpy as np
from paraview import servermanager as sm
from paraview.simple import ColorBy, GetActiveViewOrCreate, ResetCamera, SaveScreenshot, Show
from paraview.simple import XDMFReader
from vtk.util.numpy_support import vtk_to_numpy

run, xdmf, png = sys.argv[1], sys.argv[2], sys.argv[3]
f = h5py.File(run, "r")
x = f["particles/position"][:]
n = len(x)
frames = sorted((g for g in f["frames"].values() if g.attrs.get("complete", 1)),
                key=lambda g: g.attrs["step"])
times = [float(g.attrs["time"]) for g in frames]
optional = ("damage_run", "strain_energy_density", "von_mises", "stress")

reader = XDMFReader(FileNames=[xdmf])
got = [float(t) for t in reader.TimestepValues]
assert np.allclose(got, times, rtol=1e-15, atol=0), (got, times)
for g, t in zip(frames, times):
    reader.UpdatePipeline(t)
    grid = sm.Fetch(reader)
    while grid.IsA("vtkMultiBlockDataSet"):
        grid = grid.GetBlock(0)
    assert grid.GetNumberOfPoints() == n and grid.GetNumberOfCells() == n, (
        g.name, grid.GetNumberOfPoints(), grid.GetNumberOfCells())
    pts = vtk_to_numpy(grid.GetPoints().GetData())
    u = g["displacement"][:]
    assert (pts == x + u).all(), (g.name, "points are not x + u")
    pd = grid.GetPointData()
    arrays = {pd.GetArrayName(k): vtk_to_numpy(pd.GetArray(k)) for k in range(pd.GetNumberOfArrays())}
    want = {"displacement": u, "velocity": g["velocity"][:], "damage": g["damage"][:],
            "material": f["particles/material"][:], "id": f["particles/id"][:]}
    for k in optional:
        if k in g:
            want[k] = g[k][:]
    assert sorted(arrays) == sorted(want), (g.name, sorted(arrays), sorted(want))
    for k, v in want.items():
        a = arrays[k]
        v = v.reshape(n, -1) if v.ndim > 1 else v
        a = a.reshape(v.shape)
        assert a.dtype.kind == v.dtype.kind and (a == v).all(), (g.name, k, a.dtype, v.dtype)

view = GetActiveViewOrCreate("RenderView")
view.ViewSize = [400, 300]
view.ViewTime = times[-1]
shown = Show(reader, view)
ColorBy(shown, ("POINTS", "damage"))
ResetCamera(view)
SaveScreenshot(png, view, ImageResolution=[400, 300])
from vtk import vtkPNGReader  # noqa: E402

r = vtkPNGReader()
r.SetFileName(png)
r.Update()
img = r.GetOutput()
w, h, _ = img.GetDimensions()
pix = vtk_to_numpy(img.GetPointData().GetScalars()).reshape(h, w, -1)
corner, middle = pix[2, 2, :3], pix[h // 2, w // 2, :3]
assert (corner != middle).any(), "the picture is the background only"
print("ok %d" % len(frames))
