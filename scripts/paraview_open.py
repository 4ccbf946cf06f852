"""Open a kick run's particle series in ParaView and say what it read.

Run with ParaView's Python (Debian: `apt-get install paraview xvfb`):

    xvfb-run -a pvpython scripts/paraview_open.py CASE/particles/particles.pvd [SHOT.png]

It opens the .pvd through ParaView's own reader (OpenDataFile), prints the
reader, the number of time steps and, at the first three and the last,
the points, cells, point arrays and the pressure range ParaView reads;
with SHOT.png it renders the last step coloured by pressure. Exit code 1
if the reader is not ParaView's PVD reader, a step has no points, or the
pressure array is missing.
"""
import sys

from paraview.simple import (ColorBy, CreateView, OpenDataFile, Render, SaveScreenshot, Show,
                             UpdatePipeline)


def main(path, shot=None):
    src = OpenDataFile(path)
    reader = src.GetXMLName()
    print("reader:", reader)
    times = list(src.TimestepValues)
    print(f"timesteps: {len(times)}, first {times[0]}, last {times[-1]}")
    ok = reader == "PVDReader" and len(times) > 0
    for t in times[:3] + times[-1:]:
        UpdatePipeline(time=t, proxy=src)
        info = src.GetDataInformation()
        names = src.PointData.keys()
        pressure = src.PointData["pressure"].GetRange() if "pressure" in names else None
        print(f"t={t:.4f} points={info.GetNumberOfPoints()} cells={info.GetNumberOfCells()} "
              f"arrays={list(names)} pressure_range={pressure}")
        ok &= info.GetNumberOfPoints() > 0 and pressure is not None
    if shot:
        view = CreateView("RenderView")
        view.ViewSize = [800, 500]
        view.ViewTime = times[-1]
        display = Show(src, view)
        ColorBy(display, ("POINTS", "pressure"))
        display.PointSize = 2
        view.ResetCamera()
        Render(view)
        SaveScreenshot(shot, view)
        print("screenshot:", shot)
    return 0 if ok else 1


if __name__ == "__main__":
    if len(sys.argv) not in (2, 3):
        sys.exit(__doc__)
    sys.exit(main(*sys.argv[1:]))
