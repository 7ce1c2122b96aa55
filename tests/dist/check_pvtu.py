#!/usr/bin/env python3
"""VTK's own reader opens a 2-rank run's .pvtu frames and finds the one-process frame in them.

Usage: check_pvtu.py SIMIT SCENE WORK -- MPIRUN ARGS...

Runs SCENE for 2 frames in one process and with `simit run --distributed` under MPIRUN, then
reads each frame with vtkXMLUnstructuredGridReader and vtkXMLPUnstructuredGridReader: the same
cells, the same point positions once the ranks' shared points are merged, and every cell
array with the same values. Exit 0 when they agree, 1 otherwise, 77 (skipped) without VTK.
"""
import os
import shutil
import subprocess
import sys

try:
    import numpy as np
    import vtk
    from vtk.util.numpy_support import vtk_to_numpy
except ImportError as e:
    print("skipped: VTK's Python module is not importable here (%s)" % e)
    sys.exit(77)


def read(path, parallel):
    reader = vtk.vtkXMLPUnstructuredGridReader() if parallel else vtk.vtkXMLUnstructuredGridReader()
    reader.SetFileName(path)
    reader.Update()
    return reader.GetOutput()


def main():
    split = sys.argv.index("--")
    simit, scene, work = sys.argv[1:split]
    mpirun = sys.argv[split + 1:]
    shutil.rmtree(work, ignore_errors=True)
    os.makedirs(work)
    one, two = os.path.join(work, "one"), os.path.join(work, "two")
    for command in ([simit, "run", scene, "--frames", "2", "--output", one],
                    mpirun + [simit, "run", "--distributed", scene, "--frames", "2", "--output", two]):
        done = subprocess.run(command, capture_output=True, text=True, timeout=600)
        if done.returncode != 0:
            sys.exit("FAILED: %s\n%s%s" % (" ".join(command), done.stdout, done.stderr))
    failures = []
    frames = sorted(n for n in os.listdir(one) if n.endswith(".vtu"))
    for name in frames:
        a = read(os.path.join(one, name), False)
        b = read(os.path.join(two, name[:-len(".vtu")] + ".pvtu"), True)
        if a.GetNumberOfCells() != b.GetNumberOfCells() or b.GetNumberOfCells() == 0:
            failures.append("%s: %d cells in one process, %d in the .pvtu"
                            % (name, a.GetNumberOfCells(), b.GetNumberOfCells()))
            continue
        p = np.unique(vtk_to_numpy(a.GetPoints().GetData()), axis=0)
        q = np.unique(vtk_to_numpy(b.GetPoints().GetData()), axis=0)
        if p.shape != q.shape or np.abs(p - q).max() > 1e-12 * max(1.0, np.abs(p).max()):
            failures.append("%s: the point positions differ" % name)
        cells = a.GetCellData()
        for i in range(cells.GetNumberOfArrays()):
            array = cells.GetArrayName(i)
            x = np.sort(vtk_to_numpy(cells.GetArray(array)), axis=0)
            other = b.GetCellData().GetArray(array)
            if other is None:
                failures.append("%s: no cell array '%s' in the .pvtu" % (name, array))
                continue
            y = np.sort(vtk_to_numpy(other), axis=0)
            if x.shape != y.shape or np.abs(x - y).max() > 1e-12 * max(1.0, np.abs(x).max()):
                failures.append("%s: cell array '%s' differs" % (name, array))
        print("%s: %d cells, %d points (%d with the ranks' shared points twice)"
              % (name, a.GetNumberOfCells(), len(p), b.GetNumberOfPoints()))
    if not frames:
        failures.append("one process wrote no frame")
    for f in failures:
        print("FAILED: " + f)
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
