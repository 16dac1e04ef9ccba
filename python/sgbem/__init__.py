"""Read the results of `sgbem run` in Python, and run it.

    import sgbem
    run = sgbem.open("out/clamped_beam_joint")   # a run folder, or its archive.h5
    run.summary                                  # dict, as summary.json
    run.history                                  # DataFrame: one row per recorded contact state
    run.pairs("joint", state=-1)                 # DataFrame: one row per contact point
    run.thrust()                                 # DataFrame: one row per joint (thrust line)
    run.hubs()                                   # DataFrame: one row per hub (thrust_hubs.csv)
    run.contact_points(state=-1)                 # DataFrame: every pair (the VTK block "contact")
    run.to_pyvista(state=-1)                     # MultiBlock: boundary (+ field, + thrust, contact,
                                                 # + mechanism)
    sgbem.run("pipelines/x.toml", out="out/x", set={"interface.joint.cohesion": 2.0})

Everything but `hubs()` (thrust_hubs.csv, not archived) is read from `archive.h5` (h5py),
so that an archive copied away from its run folder still opens. The package hides the
archive's traps: groups come in the order of the run (the `order` attributes), not
alphabetically as h5py lists them; names are the real names (not the HDF5 group names); text
comes back as `str`, not bytes; `-0.0` comes back as `0.0`. Each DataFrame carries the
units of its columns in `df.attrs["units"]`.
"""

from ._archive import Run, open
from ._cli import SgbemError, run

__all__ = ["Run", "SgbemError", "open", "run"]
__version__ = "0.1.0"
