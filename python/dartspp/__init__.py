"""dartspp from Python: render in-process and get NumPy arrays back.

    import dartspp
    r = dartspp.render("scene.json", spp=64, seed=1)
    r.image          # (height, width, 3) float32, the gate image
    r.frames         # (frames, height, width, 3) float32, or None
    r.write_exr("out.exr")

The contract (arguments, errors, interrupts, threads) is docs/python.md; the scene format and its keys are
docs/scene-format.md and docs/keys.md, the same as for the command line.
"""

import json
import math
import numbers
import os
import signal
import threading
import warnings

import numpy as np

from . import _dartspp

__all__ = ["render", "Result", "compare", "keys", "read_image", "Error", "SceneError", "SceneWarning",
           "Interrupted"]

Error = _dartspp.Error
SceneError = _dartspp.SceneError


class SceneWarning(UserWarning):
    """Legal but suspicious input: the scene's warnings, as `dartspp render` prints them."""


class Interrupted(KeyboardInterrupt):
    """Ctrl-C (SIGINT) stopped a render; `.result` holds its completed passes (None when none had completed)."""

    def __init__(self, result):
        super().__init__("render interrupted after %d completed passes" % (result.passes if result else 0))
        self.result = result


class Result:
    """A finished render: the images, the plan it ran and its figures.

    image        (height, width, 3) float32: the gate image, as `dartspp render` writes it
    frames       (frames, height, width, 3) float32, or None without frames
    frame_times  (frames, 2) float64: each frame's [start, end), in optical path length
    plan         the resolved plan (dict), as the EXR headers and `--verbose` give it
    integrator   the plan's integrator name
    passes       completed passes (iterations)
    seconds      render time (s), loading and checks excluded
    stats        dict of the run summary's figures: camera_rays, rays, photon_paths, stored_photons, r_vol,
                 r_surf, w_gate (a delta gate's last box width, else 0), t_photon, t_maps, t_gather,
                 nonfinite_pixels (integrator.h's RENDER_FIGURES for the API)
    log          error log rows against the reference (list of dicts, the CSV columns of `--log`); [] without one
    warnings     the scene's warnings (list of str)
    interrupted  True when stopped early (the progress callback asked, or Ctrl-C)
    derivatives  (K, height, width, 3) float32: the gate image's derivative dI/dθ_k for each pointer of
                 render(derivatives=...), in its order; None when none were asked for
    derivative_frames  (K, frames, height, width, 3) float32: the frames' derivatives, or None
    amcw         (F, height, width, 3) complex64: the AMCW correlation Σ contribution·e^{−i2πft/c₀} at each of the
                 F frequencies of renderer.amcw_frequencies (docs/amcw.md); None without that key
    amcw_depth   (height, width) float32: the depth from the first two frequencies (0 where no signal), or None
    amcw_frequencies  the F frequencies in MHz, or None
    derivative_pointers  the pointers asked for (list of str, [] when none)
    waveforms    a lidar camera's (docs/lidar.md): (channels, azimuth_steps, bins) float32, the received energy
                 per unit aperture area in each range bin (bin b spans ranges [b, b + 1)·range_bin), channel 0
                 the lowest; None for another camera
    points       a lidar's echoes, (N, 8) float32: x, y, z, intensity, return number, channel, azimuth index,
                 range (the rows of <stem>_points.npy); None for another camera
    range_bin    a lidar's bin width in range (scene units); None for another camera
    """

    def __init__(self, d):
        self.image = d["image"]
        self.frames = d["frames"]
        self.frame_times = d["frame_times"]
        self.plan = json.loads(d["plan_json"])
        self.integrator = d["integrator"]
        self.passes = d["passes"]
        self.seconds = d["seconds"]
        self.interrupted = d["interrupted"]
        self.stats = d["stats"]
        self.log = [dict(zip(d["log_columns"], row.tolist())) for row in d["log"]]
        self.warnings = [w for w in d["warnings"].splitlines() if w]
        self._window = (d["gated"], d["camera_warped"], d["gate_start"], d["gate_end"])
        self._plan_json = d["plan_json"]
        self.derivatives = d["derivatives"]
        self.derivative_frames = d["derivative_frames"]
        self.derivative_pointers = list(d["derivative_pointers"])
        self.waveforms = d["waveforms"]
        self.points = d["points"]
        self.range_bin = d["range_bin"]
        self.amcw = d["amcw"]
        self.amcw_depth = d["amcw_depth"]
        self.amcw_frequencies = None if d["amcw_mhz"] is None else d["amcw_mhz"].tolist()

    def __repr__(self):
        h, w, _ = self.image.shape
        frames = "" if self.frames is None else ", %d frames" % len(self.frames)
        return "<dartspp.Result %s %dx%d%s, %d passes in %.2f s>" % (self.integrator, w, h, frames, self.passes,
                                                                     self.seconds)

    def write_exr(self, path, frames=True):
        """Writes the gate image to `path` (.exr, float32, or .pfm) with the header `dartspp render` gives it
        (time window, integrator, plan, passes), atomically; with frames=True and frames present, also
        "<stem>_NNNN<ext>" per frame, each with its own window. Returns the paths written."""
        path = os.fspath(path)
        written = [path]
        self._write(path, self.image, -1)
        if frames and self.frames is not None:
            stem, ext = os.path.splitext(path)
            digits = max(4, len(str(len(self.frames) - 1)))
            for k, img in enumerate(self.frames):
                p = "%s_%0*d%s" % (stem, digits, k, ext)
                self._write(p, img, k)
                written.append(p)
        return written

    def _write(self, path, img, frame):
        gated, warped, start, end = self._window
        _dartspp.write_image(path, img, frame, gated, warped, start, end, self.frame_times, self.integrator,
                             self._plan_json, self.passes)


def _sets(set):
    if set is None:
        return None
    if isinstance(set, dict):
        out = []
        for k, v in set.items():
            v = json.dumps(v) if isinstance(v, (bool, list, dict)) or v is None else str(v)
            out.append("%s=%s" % (k, v))
        return out
    if isinstance(set, str):
        set = [set]
    out = [str(s) for s in set]
    for s in out:
        if "=" not in s:
            raise SceneError("set: '%s' is not key=value" % s)
    return out


# include/dartspp/scene.h: DIFF_PARAM_MAX parameters at most, each pointer shorter than diff_param.pointer
DERIVATIVES_MAX = 8
_POINTER_BYTES = 255


def _derivatives(derivatives):
    """The derivatives argument checked: a list (or tuple) of at most DERIVATIVES_MAX JSON Pointers (RFC 6901),
    each a str starting with '/'. What each names is resolved by the scene's loader (it refuses a pointer to no
    parameter it can differentiate)."""
    if derivatives is None:
        return []
    if isinstance(derivatives, (str, bytes)):
        raise SceneError("derivatives: expected a list of JSON Pointers, not a single %s (write derivatives=[%r])"
                         % (type(derivatives).__name__, derivatives))
    if not isinstance(derivatives, (list, tuple)):
        raise SceneError("derivatives: expected a list of JSON Pointers (str), not %s" % type(derivatives).__name__)
    if len(derivatives) > DERIVATIVES_MAX:
        raise SceneError("derivatives: %d pointers given; a render differentiates at most %d parameters"
                         % (len(derivatives), DERIVATIVES_MAX))
    for i, p in enumerate(derivatives):
        if not isinstance(p, str):
            raise SceneError("derivatives[%d]: expected a JSON Pointer (str), not %s" % (i, type(p).__name__))
        if not p.startswith("/"):
            raise SceneError("derivatives[%d]: %r is not a JSON Pointer to a parameter (one starts with '/', "
                             "e.g. '/media/0/sigma_s')" % (i, p))
        if "\0" in p or len(p.encode("utf-8", "surrogatepass")) > _POINTER_BYTES:
            raise SceneError("derivatives[%d]: %r: a pointer has at most %d bytes and no NUL character"
                             % (i, p[:40] + "..." if len(p) > 40 else p, _POINTER_BYTES))
    return [str(p) for p in derivatives]


def _scene_text(scene):
    """A dict scene as JSON text. JSON has no NaN or Inf (json.dumps would write them anyway, and the loader could
    then only say "malformed JSON" at a column of text the user never wrote), so a non-finite number is refused
    here by its key path; NumPy numbers and arrays are written as the numbers they hold."""
    def walk(v, where):
        if isinstance(v, dict):
            for k, x in v.items():
                walk(x, "%s.%s" % (where, k) if where else str(k))
        elif isinstance(v, np.ndarray) and v.ndim == 0:
            walk(v.item(), where)
        elif isinstance(v, (list, tuple, np.ndarray)):
            for i, x in enumerate(v):
                walk(x, "%s[%d]" % (where, i))
        elif isinstance(v, numbers.Real) and not isinstance(v, (bool, np.bool_)) and not math.isfinite(v):
            raise SceneError("<dict scene>: %s: %r is not a number a scene may hold (JSON has no NaN or Inf)"
                             % (where or "(the scene)", float(v)))
        elif not isinstance(v, (str, numbers.Real, np.bool_, type(None))):
            raise SceneError("<dict scene>: %s: a %s is not a value a scene may hold (numbers, strings, booleans, "
                             "None, lists and dicts)" % (where or "(the scene)", type(v).__name__))

    def plain(v):
        if isinstance(v, np.ndarray):
            return v.tolist()
        if isinstance(v, np.generic):
            return v.item()
        raise SceneError("<dict scene>: a %s is not a value a scene may hold (numbers, strings, booleans, None, "
                         "lists and dicts)" % type(v).__name__)

    walk(scene, "")
    return json.dumps(scene, allow_nan=False, default=plain)


def _option(name, value, absent):
    """An option through the command line's own parser and range check (`dartspp render --threads`,
    src/render/options_check.c): the values the command line refuses are refused here with its message.
    The value is given as the text a user would type: a float by its repr ('nan', 'inf', '1e+30'), anything
    else by str() (True is "True", not a number)."""
    if value is None:
        return absent
    return _dartspp.check_option(name, repr(value) if isinstance(value, float) else str(value))


def render(scene, *, time=None, spp=None, seed=1, threads=None, set=None, reference=None, progress=None,
           base_dir=None, log_every=1.0, max_memory=None, derivatives=None):
    """Renders a scene and returns a Result.

    scene      a scene file's path, or a dict in the scene format (its relative paths resolve against
               base_dir, default the working folder)
    time       seconds; spp: passes. One alone is the only limit, both: whichever comes first, neither: as
               the scene says (its timeout and spp), exactly as `dartspp render --time --spp`
    seed       the random seed (the same seed and passes give the CLI's image, float for float)
    threads    None or 0: all cores
    set        overrides of integrator and renderer keys, as `--set`: {"photon_count": 1e5} or
               ["photon_count=1e5"]
    reference  an image (path, or (height, width, 3) array) to log the error against, every log_every
               seconds and at the end (Result.log)
    progress   called after every pass as progress(passes, seconds, (r_vol, r_surf)); a true return value
               stops the render after that pass (Result.interrupted), an exception stops it and propagates
    max_memory bytes the render may plan for (None: what the machine has available), or a size as
               `--max-memory` takes it ("8G")
    derivatives  JSON Pointers into the scene of parameters θ to differentiate every image by, as
               `--derivative` (at most 8): ["/media/0/sigma_s"]; Result.derivatives holds dI/dθ_k
    The options are parsed and range-checked by the command line's own code: a value `dartspp render`
    refuses raises SceneError with the same message.

    Raises SceneError (bad input, before any work; names the file or key), Error (a failure while rendering),
    Interrupted (Ctrl-C, a KeyboardInterrupt carrying the completed passes as .result). Nothing is printed:
    the scene's warnings are issued as SceneWarning (and kept in Result.warnings). The GIL is released while
    rendering.
    """
    text = name = None
    path = None
    if isinstance(scene, dict):
        text = _scene_text(scene)
        name = "<dict scene>"
        base_dir = os.path.abspath(os.fspath(base_dir)) if base_dir is not None else os.getcwd()
    elif isinstance(scene, (str, os.PathLike)):
        path = os.fspath(scene)
        if base_dir is not None:
            raise SceneError("base_dir: only for a dict scene (a scene file's paths resolve against its folder)")
    else:
        raise SceneError("scene: expected a path or a dict in the scene format, not %s" % type(scene).__name__)
    threads, seed = _option("threads", threads, 0), _option("seed", seed, 1)
    spp, time = _option("spp", spp, -1), _option("time", time, -1.0)
    max_memory, log_every = _option("max_memory", max_memory, 0.0), _option("log_every", log_every, 1.0)
    ref_path = ref_array = None
    if reference is not None:
        if isinstance(reference, (str, os.PathLike)):
            ref_path = os.fspath(reference)
        else:
            ref_array = reference
    pointers = _derivatives(derivatives)
    if progress is not None and not callable(progress):
        raise SceneError("progress: expected a callable, not %s" % type(progress).__name__)
    catch = threading.current_thread() is threading.main_thread() and \
        signal.getsignal(signal.SIGINT) is signal.default_int_handler
    d = _dartspp.render(path, text, name, base_dir, _sets(set), seed, spp, float(time), threads, float(max_memory),
                        ref_path, ref_array, float(log_every), progress, catch, pointers or None)
    d["derivative_pointers"] = pointers
    result = Result(d)
    for w in result.warnings:
        warnings.warn(w, SceneWarning, stacklevel=2)
    if d["sigint"]:
        raise Interrupted(result if result.passes > 0 else None)
    return result


def compare(image, reference):
    """The metrics of `dartspp compare` of an image against a reference (arrays of shape (height, width, 3),
    or paths): dict with mse, rmse, rel_mse (mean of (x-r)^2/(r^2+0.01)), mse_q99 (both divided by the
    reference's 0.99 quantile q99), q99, nonfinite and pixels. A NaN or Inf pixel raises SceneError."""
    if isinstance(image, (str, os.PathLike)):
        image = read_image(image)
    if isinstance(reference, (str, os.PathLike)):
        reference = read_image(reference)
    a, b = np.asarray(image), np.asarray(reference)
    if a.shape != b.shape:
        raise SceneError("compare: the image is %s but the reference is %s" % (a.shape, b.shape))
    return _dartspp.compare(a, b)


def read_image(path):
    """An EXR or PFM image as a (height, width, 3) float32 array, row 0 at the top."""
    return _dartspp.read_image(os.fspath(path))


def keys():
    """The key table (docs/keys.md), one dict per key: section, name, type, default, range, read_by,
    changes_image, meaning."""
    return _dartspp.keys()
