"""gradel: real-time elastic bodies from voxel volumes (Miyazaki et al. 2002 gradational layout).

The compiled engine (python/gradel_module.cpp) is the extension module ``gradel.gradel``; its
names are re-exported here. ``gradel.study`` (pure Python) runs parameter studies on a Dask
cluster (docs/study.md).
"""
from .gradel import Body, InputError, Simulation, check_scene, load_volume

__all__ = ["Body", "InputError", "Simulation", "check_scene", "load_volume"]
__version__ = "0.1.0"
