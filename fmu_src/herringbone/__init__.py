"""Dynamics of a herringbone Novikov gear train (see MODEL.md): scenes, model, reference run,
the fast (compiled) run."""
from .scene import Scene, SceneError, load_scene, scene_from_dict

__all__ = ["Scene", "SceneError", "load_scene", "scene_from_dict"]
from .reference import reference_simulate
from .integrator import simulate

__all__ += ["reference_simulate", "simulate"]
from .sweep import sweep

__all__ += ["sweep"]
