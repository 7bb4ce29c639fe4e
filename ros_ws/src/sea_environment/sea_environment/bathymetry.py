"""Bathymetry: water depth on a regular grid, read from an ESRI ASCII grid file and
interpolated bilinearly with scipy's RegularGridInterpolator. Pure numpy/scipy, no ROS.

File format (ESRI ASCII raster, the plain-text grid GIS tools such as GDAL and QGIS read and
write; https://desktop.arcgis.com/en/arcmap/latest/manage-data/raster-and-images/esri-ascii-raster-format.htm)::

    ncols         4
    nrows         3
    xllcorner     -100.0        # or xllcenter / yllcenter: the lower-left cell's centre
    yllcorner     -50.0
    cellsize      50.0
    NODATA_value  -9999         # optional: land (depth 0, a vessel there is aground)
    12.0 12.5 13.0 14.0         # nrows lines of ncols values, the NORTHERNMOST row first
    10.0 11.0 12.0 13.0
     8.0  9.0 10.0 11.0

Coordinates are the scenario's map frame (ENU metres about its origin: x east, y north); values
are water depths in metres, positive down from the still water surface; 0 is dry. A negative
value, a missing or malformed header line, a row of the wrong length or a non-number fails with
the file, the line and the entry named. Values at cell centres; between centres bilinear; outside
the grid the nearest edge value (the grid should cover the area the run sails in).
"""
from __future__ import annotations

import math
import os

import numpy as np
from numba import njit



class BathymetryError(ValueError):
    """A depth grid file that cannot be used; the message names the file and the entry."""


class DepthGrid:
    def __init__(self, x: np.ndarray, y: np.ndarray, depth_yx: np.ndarray, source: str = "<grid>"):
        self.x, self.y, self.values, self.source = x, y, depth_yx, source
        # imported here: scipy.interpolate costs every node process 0.25 s at start-up, and only a
        # run with a depth grid needs it
        from scipy.interpolate import RegularGridInterpolator
        self._interp = RegularGridInterpolator((y, x), depth_yx, method="linear")
        self.bounds = (float(x[0]), float(x[-1]), float(y[0]), float(y[-1]))

    @staticmethod
    def load(path: str) -> "DepthGrid":
        if not os.path.isfile(path):
            raise BathymetryError(f"{path}: depth grid file not found")
        with open(path) as f:
            lines = [(i + 1, ln.split("#")[0].split()) for i, ln in enumerate(f)]
        lines = [(n, parts) for n, parts in lines if parts]
        head, rows = _read_header(path, lines)
        centre = "xllcenter" in head
        ncols, nrows, cs = head["ncols"], head["nrows"], head["cellsize"]
        nodata = head.get("nodata_value")
        if len(rows) != nrows:
            raise BathymetryError(f"{path}: {len(rows)} rows of depths, the header says nrows {nrows}")
        for n, parts in rows:  # before any allocation: the grid is no larger than the file
            if len(parts) != ncols:
                raise BathymetryError(f"{path}: line {n}: {len(parts)} values, the header says ncols {ncols}")
        grid = np.empty((nrows, ncols))
        for r, (n, parts) in enumerate(rows):
            for c, text in enumerate(parts):
                try:
                    v = float(text)
                except ValueError:
                    raise BathymetryError(f"{path}: line {n}, column {c + 1}: {text!r} is not a number") from None
                if nodata is not None and v == nodata:
                    v = 0.0                                   # land
                elif not math.isfinite(v) or v < 0.0:
                    raise BathymetryError(f"{path}: line {n}, column {c + 1}: depth {text} m is negative or "
                                          f"not finite (depths are positive down; land is 0 or NODATA_value)")
                grid[r, c] = v
        x0 = head["xllcenter"] if centre else head["xllcorner"] + 0.5 * cs
        y0 = head["yllcenter"] if centre else head["yllcorner"] + 0.5 * cs
        x = x0 + cs * np.arange(ncols)
        y = y0 + cs * np.arange(nrows)
        return DepthGrid(x, y, grid[::-1].copy(), os.path.abspath(path))   # file: north row first

    def depth_at(self, x, y):
        """Depth (m) at world (x, y): a float for scalars, an array for arrays. Scalars (a vessel's
        position, every step) go through `bilinear`; arrays through scipy."""
        if np.ndim(x) == 0:
            ny, nx = self.values.shape
            return bilinear(self.x[0], self.x[1] - self.x[0], self.y[0], self.y[1] - self.y[0], self.values.ravel(),
                            0, nx, ny, float(x), float(y))
        xmin, xmax, ymin, ymax = self.bounds
        xs = np.clip(np.asarray(x, float), xmin, xmax)
        ys = np.clip(np.asarray(y, float), ymin, ymax)
        return self._interp(np.stack([ys, xs], axis=-1))


_HEADER_KEYS = ("ncols", "nrows", "xllcorner", "yllcorner", "xllcenter", "yllcenter", "cellsize", "nodata_value")


def _read_header(path: str, lines):
    """The ESRI ASCII grid header (key -> number; ncols, nrows as int) and the lines after it.
    Each key once, known, finite; the lower-left given either as corner or as centre for both
    axes; ncols, nrows whole numbers >= 2, cellsize > 0."""
    head, where = {}, {}
    for k, (n, parts) in enumerate(lines):
        key = parts[0].lower()
        if key[0].isdigit() or key[0] in "+-.":
            break
        if len(parts) != 2:
            raise BathymetryError(f"{path}: line {n}: expected '<key> <value>', got {' '.join(parts)!r}")
        if key not in _HEADER_KEYS:
            raise BathymetryError(f"{path}: line {n}: unknown header key {parts[0]!r} (ESRI ASCII grid: "
                                  f"{', '.join(_HEADER_KEYS)})")
        if key in head:
            raise BathymetryError(f"{path}: line {n}: header key '{key}' given again (first on line {where[key]})")
        try:
            head[key] = float(parts[1])
        except ValueError:
            raise BathymetryError(f"{path}: line {n}: {parts[0]} {parts[1]!r} is not a number") from None
        if not math.isfinite(head[key]):
            raise BathymetryError(f"{path}: line {n}: {parts[0]} {parts[1]} is not a finite number")
        where[key] = n
    else:
        raise BathymetryError(f"{path}: no depth values after the header")
    corner = [k for k in ("xllcorner", "yllcorner") if k in head]
    centre = [k for k in ("xllcenter", "yllcenter") if k in head]
    if corner and centre:
        raise BathymetryError(f"{path}: the lower-left is given both as corner ({', '.join(corner)}) and as "
                              f"centre ({', '.join(centre)}): give xllcorner and yllcorner, or xllcenter and yllcenter")
    need = ("ncols", "nrows", "xllcenter" if centre else "xllcorner", "yllcenter" if centre else "yllcorner",
            "cellsize")
    for key in need:
        if key not in head:
            raise BathymetryError(f"{path}: header key '{key}' is missing (ESRI ASCII grid: {', '.join(need)})")
    ncols, nrows = head["ncols"], head["nrows"]
    if ncols != int(ncols) or nrows != int(nrows) or ncols < 2 or nrows < 2:
        raise BathymetryError(f"{path}: ncols {ncols:g} and nrows {nrows:g} must be whole numbers >= 2")
    if head["cellsize"] <= 0.0:
        raise BathymetryError(f"{path}: cellsize {head['cellsize']!r} must be a finite number > 0")
    head["ncols"], head["nrows"] = int(ncols), int(nrows)
    return head, lines[k:]


@njit(cache=True)
def bilinear(x0, dx, y0, dy, values, at, nx, ny, x, y):
    """Bilinear interpolation on the regular grid (its ny x nx depths row-major in the flat
    array values from index `at`: a view of them costs the samplers more than this), clamped
    to its edges: what RegularGridInterpolator computes for one point (the tests compare the
    two), hand-written because scipy's call costs about 26 us, five times a whole vessel model
    step (measured, benchmarks/bench_vessels.py), and the models ask once per step and body."""
    fx = min(max((x - x0) / dx, 0.0), nx - 1.0)
    fy = min(max((y - y0) / dy, 0.0), ny - 1.0)
    i = min(int(fx), nx - 2)
    j = min(int(fy), ny - 2)
    wx = fx - i
    wy = fy - j
    k = at + j * nx + i
    return ((1.0 - wy) * ((1.0 - wx) * values[k] + wx * values[k + 1])
            + wy * ((1.0 - wx) * values[k + nx] + wx * values[k + nx + 1]))
