"""check_dump.py RUN.h5 PVD RAW_PVD PNG KIND... -- run under ParaView's own
pvbatch (paraview.bats): ParaView reads pd-dump2vtk's collection PVD
(compressed) and RAW_PVD (--compress 0) at every frame's time and finds
  - the frames' times as its time steps;
  - per time, the blocks "particles" and then one per KIND (indenter,
    projectile), in that order;
  - the particles at x + u with the frame's displacement and velocity bit
    for bit, and every point array equal to tests/vtu.py's reading of the
    same file;
  - each sphere a closed surface of radius R about the centre the run
    gives it, whose area ParaView's own IntegrateVariables puts within 2%
    of 4 pi R^2;
  - the compressed and the raw collection the same, array by array.
Then it draws the last frame (particles coloured by damage, the spheres)
into PNG and reads it back: the middle is not the background.  Prints
"ok NFRAMES".
"""
import os
import sys

import h5py
import numpy as np
from paraview import servermanager as sm
from paraview.simple import (ColorBy, GetActiveViewOrCreate, IntegrateVariables, PVDReader,
                             ExtractBlock, MergeBlocks, ResetCamera, SaveScreenshot, Show)
from vtk.util.numpy_support import vtk_to_numpy

import vtu

run, pvd, raw_pvd, png, kinds = sys.argv[1], sys.argv[2], sys.argv[3], sys.argv[4], sys.argv[5:]
f = h5py.File(run, "r")
sc = f["scene"].attrs
x = f["particles/position"][:]
frames = sorted(f["frames"].values(), key=lambda g: g.attrs["step"])
times = [float(g.attrs["time"]) for g in frames]


def blocks(reader, t):
    """The blocks of the collection at time t: name -> vtkUnstructuredGrid."""
    reader.UpdatePipeline(t)
    mb = sm.Fetch(reader)
    if not mb.IsA("vtkMultiBlockDataSet"):  # one part: ParaView gives it alone
        return {"particles": mb}
    out = {}
    for b in range(mb.GetNumberOfBlocks()):
        name = mb.GetMetaData(b).Get(mb.NAME())
        grid = mb.GetBlock(b)
        while grid.IsA("vtkMultiBlockDataSet"):  # a part is a block of one piece
            assert grid.GetNumberOfBlocks() == 1
            grid = grid.GetBlock(0)
        out[name] = grid
    return out


def arrays(grid):
    pd = grid.GetPointData()
    a = {pd.GetArrayName(k): vtk_to_numpy(pd.GetArray(k)) for k in range(pd.GetNumberOfArrays())}
    a["Points"] = vtk_to_numpy(grid.GetPoints().GetData())
    return a


def sphere_of(kind, g):
    step = int(g.attrs["step"])
    if kind == "indenter":
        row = sc["indenter"]
        return row[:3] + (step * sc["dt"]) * row[5:8], row[3]
    return g.attrs["projectile_position"], sc["projectile"][3]


zr, rr = PVDReader(FileName=pvd), PVDReader(FileName=raw_pvd)
for r in (zr, rr):
    assert np.allclose(list(r.TimestepValues), times, rtol=1e-15, atol=0), (r.TimestepValues, times)
out = os.path.dirname(pvd)
for g, t in zip(frames, times):
    step = int(g.attrs["step"])
    z, r = blocks(zr, t), blocks(rr, t)
    assert list(z) == ["particles"] + kinds, list(z)
    assert list(r) == list(z)
    p = arrays(z["particles"])
    assert np.array_equal(p["displacement"], g["displacement"][:])
    assert np.array_equal(p["velocity"], g["velocity"][:])
    assert np.abs(p["Points"] - (x + g["displacement"][:])).max() <= 1e-12
    mine = vtu.read(os.path.join(out, "%s_%08d.vtu" % (os.path.basename(pvd)[:-4], step)))
    assert mine.compressed
    assert sorted(mine.point_data) == sorted(k for k in p if k != "Points")
    for k, v in mine.point_data.items():
        assert np.array_equal(p[k].reshape(v.shape), v), k
    for name in z:
        a, b = arrays(z[name]), arrays(r[name])
        assert sorted(a) == sorted(b), name
        for k in a:
            assert np.array_equal(a[k], b[k]), (name, k)
    for kind in kinds:
        s = z[kind]
        c, R = sphere_of(kind, g)
        pts = arrays(s)["Points"]
        assert np.allclose(np.linalg.norm(pts - c, axis=1), R, rtol=1e-12)
        assert s.GetNumberOfCells() == 960 and all(s.GetCellType(k) == 5 for k in range(960))
    if kinds:
        # ParaView's own surface integral over each sphere
        zr.UpdatePipeline(t)
        for k, kind in enumerate(kinds):
            one = MergeBlocks(Input=ExtractBlock(Input=zr, Selectors=["/Root/" + kind]))
            area = sm.Fetch(IntegrateVariables(Input=one)).GetCellData().GetArray("Area")
            c, R = sphere_of(kind, g)
            assert abs(area.GetValue(0) / (4 * np.pi * R**2) - 1) < 0.02, (kind, area.GetValue(0))

# the last frame drawn: ParaView renders what it read
view = GetActiveViewOrCreate("RenderView")
view.ViewSize = [400, 300]
view.ViewTime = times[-1]
ColorBy(Show(zr, view), ("POINTS", "damage"))
ResetCamera(view)
SaveScreenshot(png, view, ImageResolution=[400, 300])
from vtkmodules.vtkIOImage import vtkPNGReader
img = vtkPNGReader()
img.SetFileName(png)
img.Update()
w, h, _ = img.GetOutput().GetDimensions()
rgb = vtk_to_numpy(img.GetOutput().GetPointData().GetScalars()).reshape(h, w, -1)[:, :, :3]
# the body (and a sphere over it) in the middle, the background at a corner
assert (w, h) == (400, 300) and not np.array_equal(rgb[h // 2, w // 2], rgb[2, 2]), rgb[h // 2, w // 2]
print("ok", len(frames))
