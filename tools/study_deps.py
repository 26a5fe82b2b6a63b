"""Makes the Python modules of tools/study and tools/make_refs.py importable (numpy, OpenImageIO,
matplotlib). The packages themselves are listed and installed by tools/bootstrap.sh (group `study`),
the project's one installer; this only decides when to call it and which interpreter to run."""
import importlib
import os
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
SYSTEM_PYTHON = "/usr/bin/python3"


def _missing(modules):
    missing = []
    for m in modules:
        try:
            importlib.import_module(m)
        except ImportError:
            missing.append(m)
    return missing


def ensure_packages(modules=("numpy", "OpenImageIO", "matplotlib"), install=True):
    """Return when `modules` import. Otherwise: the Debian packages serve the system interpreter, and
    a pyenv/venv python3 earlier on PATH does not see them, so hand over to /usr/bin/python3 (same
    arguments) when that is not us; there, run `bash tools/bootstrap.sh --install study` and retry."""
    missing = _missing(modules)
    if not missing:
        return
    if os.path.exists(SYSTEM_PYTHON) and os.path.realpath(sys.executable) != os.path.realpath(SYSTEM_PYTHON):
        os.execv(SYSTEM_PYTHON, [SYSTEM_PYTHON] + sys.argv)
    if install:
        subprocess.run(["bash", os.path.join(HERE, "bootstrap.sh"), "--install", "study"], check=True)
        importlib.invalidate_caches()
        missing = _missing(modules)
    if missing:
        sys.exit(f"{os.path.basename(sys.argv[0])}: Python modules missing: {' '.join(missing)} "
                 f"(install them with: bash tools/bootstrap.sh --install study)")
