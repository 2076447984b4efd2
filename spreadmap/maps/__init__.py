"""Processing design maps from the surrogate, with their uncertainty; the DEM sample and regimes.

``grids`` computes (evaluated design grids, support, regime probabilities, the effect of friction,
the machine map's y axis); one module per figure: ``machine`` (machine map), ``powder_maps``
(band and cluster maps), ``parallel`` (parallel coordinates of the DEM cases), ``regimes``. The
machine, powder and regime maps compute their numbers apart from drawing them (``powder_band_grid``
then ``draw_powder_band_map``, ...), so a figure can be redrawn from its CSV;
``labels`` places line labels, ``style`` holds what the figures share, ``validation_note`` the
line under the title of a map drawn from another model than the maps' (its validation against the
noise). Every figure takes ``floor`` (spreadmap.case.substrate.floor_label of the config its cases
ran with) and names it above its title and in its CSV (spreadmap.figures.save_figure).
"""
from .grids import choose_machine_y, machine_y_axis
from .machine import machine_grid, machine_map
from .parallel import best_case, parallel_coordinates
from .powder_maps import powder_band_map, powder_cluster_map
from .regimes import REGIMES, regime_overlay
from .style import MapResult
from .validation_note import validation_note

__all__ = ["MapResult", "machine_map", "machine_grid", "powder_band_map", "powder_cluster_map", "parallel_coordinates",
           "best_case", "regime_overlay", "REGIMES", "choose_machine_y", "machine_y_axis", "validation_note"]
