"""The environment to start Debian's Blender in from a test.

Debian's Blender embeds the system's Python 3.11 but finds its home from
the first `python3.11` on PATH. CTest started through a pyenv shim (pip's
CMake on a machine with pyenv first on PATH) runs with pyenv's own Python
folders put in front of PATH, and Blender then takes pyenv's Python as its
home: the system's site-packages (numpy among them) vanish from its
sys.path. The folders of pyenv and of virtual environments are therefore
taken off PATH, and PYTHONHOME / PYTHONPATH / VIRTUAL_ENV unset."""
import os


def blender_env(extra=None):
    env = dict(os.environ)
    keep = [p for p in env.get("PATH", "").split(os.pathsep)
            if p and ".pyenv" not in p and not os.path.isfile(os.path.join(p, "pyvenv.cfg"))
            and not os.path.isfile(os.path.join(os.path.dirname(p), "pyvenv.cfg"))]
    env["PATH"] = os.pathsep.join(keep or ["/usr/bin", "/bin"])
    for key in ("PYTHONHOME", "PYTHONPATH", "VIRTUAL_ENV", "PYENV_VERSION"):
        env.pop(key, None)
    env.update(extra or {})
    return env
