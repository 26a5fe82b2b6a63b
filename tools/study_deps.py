"""Debian packages the convergence study needs, installed when missing (quiet when present).

Same policy as tools/bootstrap.sh: dpkg-query for what is installed, apt-get --no-install-recommends
for what is not, through sudo when not root. numpy computes the metrics the renderer does not print,
OpenImageIO's Python binding reads the EXRs, matplotlib draws the charts.
"""
import os
import shutil
import subprocess
import sys

PACKAGES = ["python3-numpy", "python3-openimageio", "python3-matplotlib"]


def _installed(package):
    r = subprocess.run(["dpkg-query", "-W", "-f=${Status}", package],
                       stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True)
    return r.returncode == 0 and "install ok installed" in r.stdout


def ensure_packages():
    """Install the missing packages; exit with a clear message when that is impossible."""
    if shutil.which("dpkg-query") is None:
        return  # not Debian: assume the modules come from elsewhere; the imports will say if not
    missing = [p for p in PACKAGES if not _installed(p)]
    if not missing:
        return
    sudo = []
    if os.geteuid() != 0:
        if shutil.which("sudo") is None:
            sys.exit("study: these packages are missing and I am not root (no sudo): " + " ".join(missing))
        sudo = ["sudo"]
    print("study: installing " + " ".join(missing), file=sys.stderr, flush=True)
    env = dict(os.environ, DEBIAN_FRONTEND="noninteractive")
    subprocess.run(sudo + ["env", "DEBIAN_FRONTEND=noninteractive", "apt-get", "update", "-qq"],
                   check=True, stdout=subprocess.DEVNULL, env=env)
    subprocess.run(sudo + ["env", "DEBIAN_FRONTEND=noninteractive", "apt-get", "install", "-y", "-qq",
                           "--no-install-recommends"] + missing,
                   check=True, stdout=subprocess.DEVNULL, env=env)
