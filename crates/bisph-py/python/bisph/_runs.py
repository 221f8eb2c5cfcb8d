"""Reading the output folder of a finished run: its CSV series, summary and VTK frames."""

from __future__ import annotations

import csv
import json
import re
import xml.etree.ElementTree as ET
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Dict, List, Optional, Union

import numpy as np

try:
    import pandas as _pandas
except ImportError:  # pandas is optional: tables are then dicts of arrays
    _pandas = None

#: A CSV series: a pandas DataFrame when pandas is installed, else a dict of column arrays.
Table = Any

_VTK_TYPES = {"Float64": "<f8", "Int64": "<i8", "UInt8": "u1"}


def _read_table(path: Path) -> Optional[Table]:
    """A CSV series of a run (header, then rows; text columns such as ``body`` stay text)."""
    if not path.is_file():
        return None
    if _pandas is not None:
        return _pandas.read_csv(path)
    with path.open(newline="") as f:
        rows = list(csv.reader(f))
    header, body = rows[0], rows[1:]
    columns: Dict[str, np.ndarray] = {}
    for k, name in enumerate(header):
        values = [r[k] for r in body]
        try:
            columns[name] = np.array([float(v) for v in values], dtype=np.float64)
        except ValueError:
            columns[name] = np.array(values, dtype=str)
    return columns


def _read_vtu(path: Path) -> Dict[str, np.ndarray]:
    """The points, point data and cell data of a ``.vtu`` file as bisph writes it (raw
    appended little-endian data with UInt64 block sizes)."""
    raw = path.read_bytes()
    start = raw.index(b"<AppendedData")
    data = raw[raw.index(b"_", start) + 1 :]
    header = raw[:start].decode()
    arrays: Dict[str, np.ndarray] = {}
    for section, prefix in (("PointData", ""), ("CellData", "cell_"), ("Points", "")):
        match = re.search(rf"<{section}>(.*?)</{section}>", header, re.S)
        if match is None:
            continue
        for tag in re.finditer(r"<DataArray ([^>]*)/>", match.group(1)):
            attrs = dict(re.findall(r'(\w+)="([^"]*)"', tag.group(1)))
            offset = int(attrs["offset"])
            size = int(np.frombuffer(data, "<u8", 1, offset)[0])
            dtype = np.dtype(_VTK_TYPES[attrs["type"]])
            values = np.frombuffer(data, dtype, size // dtype.itemsize, offset + 8).copy()
            components = int(attrs.get("NumberOfComponents", "1"))
            if components > 1:
                values = values.reshape(-1, components)
            name = "points" if section == "Points" else prefix + attrs["Name"]
            arrays[name] = values
    return arrays


@dataclass
class Frames:
    """A ParaView series (``fluid.pvd`` or ``walls.pvd``): the frame times and a reader of
    each frame's arrays (``frame(k)``; loaded on demand)."""

    folder: Path
    #: Simulated time of each frame [s].
    times: np.ndarray
    #: Each frame's ``.vtu`` file, relative to the run folder.
    files: List[str]

    def __len__(self) -> int:
        return len(self.files)

    def frame(self, k: int) -> Dict[str, np.ndarray]:
        """Frame ``k``: ``points`` (n, 3) [m] and the point data by name (for the fluid
        ``velocity`` (n, 3) [m/s], ``acceleration``, ``pressure`` [Pa], ``density``
        [kg/m^3], ``id``; for the walls the element data, prefixed ``cell_``)."""
        return _read_vtu(self.folder / self.files[k])


def _read_pvd(folder: Path, name: str) -> Optional[Frames]:
    path = folder / name
    if not path.is_file():
        return None
    sets = ET.parse(path).getroot().iter("DataSet")
    entries = [(float(d.get("timestep", "nan")), d.get("file", "")) for d in sets]
    times = np.array([t for t, _ in entries], dtype=np.float64)
    return Frames(folder, times, [f for _, f in entries])


@dataclass
class Run:
    """The outputs of a run (see docs/outputs-and-errors.md for every column). Tables are
    pandas DataFrames when pandas is installed, else dicts of NumPy arrays; a file the run
    did not write is ``None``."""

    folder: Path
    #: ``energy.csv``: t, kinetic, compressible, potential, wall_work, total,
    #: viscous_dissipation, forcing_work, diffusion_dissipation, removed [J; J/m in 2-D].
    energy: Table
    #: ``forces.csv``: t, body, fx, fy (fz, mx, my, mz in 3-D) [N; N/m in 2-D].
    forces: Optional[Table]
    #: ``probes.csv``: t and one column per probe [Pa or m].
    probes: Optional[Table]
    #: Pistons (``bodies.csv``) and free bodies (``body_<name>.csv``), by name
    #: (``"pistons"`` for ``bodies.csv``).
    bodies: Dict[str, Table]
    #: ``summary.json``.
    summary: Dict[str, Any]
    #: ``settling.json`` (``None`` when the run did not settle).
    settling: Optional[Dict[str, Any]]
    #: ``fluid.pvd``: the particle frames.
    fluid: Optional[Frames]
    #: ``walls.pvd``: the boundary-element frames.
    walls: Optional[Frames]
    #: Other series the case wrote (``midpoint``, ``flux``), by name.
    extra: Dict[str, Table] = field(default_factory=dict)


def read_run(folder: Union[str, Path]) -> Run:
    """Reads the output folder of a finished run (``bisph run`` or ``Simulation.run`` with
    ``out=``). Raises ``FileNotFoundError`` when the folder has no ``energy.csv``."""
    folder = Path(folder)
    energy = _read_table(folder / "energy.csv")
    if energy is None:
        raise FileNotFoundError(f"{folder}: no energy.csv (not the output folder of a run)")
    bodies: Dict[str, Table] = {}
    pistons = _read_table(folder / "bodies.csv")
    if pistons is not None:
        bodies["pistons"] = pistons
    for path in sorted(folder.glob("body_*.csv")):
        bodies[path.stem[len("body_") :]] = _read_table(path)
    extra = {name: _read_table(folder / f"{name}.csv") for name in ("midpoint", "flux")}

    def read_json(name: str) -> Optional[Dict[str, Any]]:
        path = folder / name
        return json.loads(path.read_text()) if path.is_file() else None

    return Run(
        folder=folder,
        energy=energy,
        forces=_read_table(folder / "forces.csv"),
        probes=_read_table(folder / "probes.csv"),
        bodies=bodies,
        summary=read_json("summary.json") or {},
        settling=read_json("settling.json"),
        fluid=_read_pvd(folder, "fluid.pvd"),
        walls=_read_pvd(folder, "walls.pvd"),
        extra={k: v for k, v in extra.items() if v is not None},
    )
