"""Runs `tessera render --json` and `tessera compare --json` for the convergence study.

Every render gets its own seed, so all points of a series are independent (renders of one seed at
4 and 8 spp would share their first 4 samples per pixel, because samples are seeded by
(pixel, sample index, seed)). Budgets are a geometric series in spp, not in seconds: spp gives the
same image on a loaded machine, and the measured seconds go on the chart's axis.
"""
import json
import os
import re
import subprocess


class RenderError(RuntimeError):
    pass


class Tessera:
    def __init__(self, binary, threads, timeout):
        self.binary = binary
        self.threads = threads
        self.timeout = timeout

    def _names(self, label):
        """Names listed in `tessera render --help` after `label` (e.g. 'light transport algorithm')."""
        text = subprocess.run([self.binary, "render", "--help"], stdout=subprocess.PIPE,
                              stderr=subprocess.STDOUT, text=True).stdout
        m = re.search(re.escape(label) + r":\s*(.*?)\(default", text, re.S)
        if not m:
            raise RenderError(f"cannot find '{label}' in `tessera render --help`")
        return [n.strip() for n in re.sub(r"\s+", " ", m.group(1)).split(",") if n.strip()]

    def integrators(self):
        return self._names("light transport algorithm")

    def samplers(self):
        return ["sobol", "independent"]

    def accels(self):
        return self._names("acceleration structure")

    def render(self, scene, out, integrator, accel, spp, seed, resolution, max_depth=None):
        """One render; returns the parsed --json object (raises RenderError on failure or timeout).
        `integrator` is a series label: a name, or NAME/SAMPLER (e.g. ptnee/independent)."""
        name, _, sampler = integrator.partition("/")
        cmd = [self.binary, "render", scene, "-o", out, "--no-png", "--quiet", "--json",
               "--integrator", name, "--accel", accel, "--spp", str(spp), "--seed", str(seed),
               "--threads", str(self.threads)]
        if sampler:
            cmd += ["--sampler", sampler]
        if resolution is not None:
            cmd += ["--resolution", f"{resolution[0]}x{resolution[1]}"]
        if max_depth is not None:
            cmd += ["--max-depth", str(max_depth)]
        try:
            r = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                               timeout=self.timeout)
        except subprocess.TimeoutExpired:
            raise RenderError(f"timed out after {self.timeout} s: {' '.join(cmd)}")
        except OSError as e:  # e.g. the binary being relinked under us
            raise RenderError(f"cannot run {self.binary}: {e}")
        if r.returncode != 0:
            raise RenderError(f"exit {r.returncode}: {' '.join(cmd)}\n{r.stderr.strip()}")
        lines = [l for l in r.stdout.splitlines() if l.startswith("{")]
        if not lines:
            raise RenderError(f"no JSON from: {' '.join(cmd)}")
        j = json.loads(lines[-1])
        j["command"] = " ".join(cmd)
        return j

    def compare(self, test, ref):
        cmd = [self.binary, "compare", test, ref, "--json"]
        try:
            r = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        except OSError as e:
            raise RenderError(f"cannot run {self.binary}: {e}")
        if r.returncode != 0:
            raise RenderError(f"exit {r.returncode}: {' '.join(cmd)}\n{r.stderr.strip()}")
        return json.loads(r.stdout.strip().splitlines()[-1])


def spp_series(sec_per_spp, max_seconds, budgets, max_spp):
    """Geometric spp series (factor 2) of `budgets` points whose largest render takes about
    max_seconds: the largest power of two that fits, but never fewer than `budgets` distinct points."""
    top = 1
    while top * 2 * sec_per_spp <= max_seconds and top * 2 <= max_spp:
        top *= 2
    top = max(top, 2 ** (budgets - 1))
    return [top >> k for k in range(budgets - 1, -1, -1)]


def find_binary(root):
    build = os.environ.get("TESSERA_BUILD", os.path.join(root, "build"))
    return os.path.join(build, "src", "tessera")
