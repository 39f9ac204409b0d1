"""Finding the Python module tightex: the folder the add-on's preferences name, else PYTHONPATH or
wherever pip installed it. The reason it is missing is kept for the UI to show."""

import importlib
import sys

_state = {"module": None, "error": None}


def _folder():
    import bpy
    addon = bpy.context.preferences.addons.get(__package__)
    return bpy.path.abspath(addon.preferences.module_folder) if addon and addon.preferences.module_folder else ""


def forget():
    """Look again on the next load (the preference changed)."""
    _state["module"] = None
    _state["error"] = None


def load():
    """(the module tightex, None) or (None, a message saying why it cannot be imported and what to do)."""
    if _state["module"] is not None or _state["error"] is not None:
        return _state["module"], _state["error"]
    folder = _folder()
    if folder and folder not in sys.path:
        sys.path.insert(0, folder)
    try:
        module = importlib.import_module("tightex")
        if not hasattr(module, "optimize_arrays"):
            raise ImportError(f"{getattr(module, '__file__', 'tightex')} has no optimize_arrays (an older tightex?)")
        _state["module"] = module
    except Exception as e:  # ImportError, or a module built for another Python
        where = f"the folder '{folder}'" if folder else "Blender's Python path"
        _state["error"] = (f"Cannot import tightex from {where}: {e}\n"
                           f"Blender runs Python {sys.version.split()[0]}: build tightex for it and name BUILD/python "
                           "in the add-on's preferences, or pip install it")
    return _state["module"], _state["error"]
