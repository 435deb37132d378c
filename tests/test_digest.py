"""The bundled sample's ``run`` outputs against a stored digest (behaviour unchanged).

``tests/data/sample_run_digest.json`` holds, for every output of ``run`` on
``sample_data/gl073a_sim.h5`` with its defaults: every number and string of the JSON
outputs and of ``modes.csv`` (a path → value table), and for every dataset of ``frf.h5``
and ``modal.h5`` its shape, dtype and three float64 sums (of the values, of their
magnitudes, and weighted by a ramp, so that a moved or changed value shows), plus the
files' attributes. What is left out is what must differ between two identical runs:
times, paths, checksums of files (they hold paths and times), the provenance block.

A refactor must leave this unchanged; a change of behaviour regenerates it on purpose,
in its own commit that says why::

    python tests/test_digest.py --write

**One digest per numerics** (session 30). The file holds a digest for each machine kind it
was written on, keyed by :func:`numerics` (numpy's and scipy's versions and the BLAS
libraries they load, whose kernels follow the CPU). A run is compared with the digest of
its own numerics number by number (below); on numerics with no digest of its own, with every
stored one at the portable level (:func:`portable`): what a reader of the tables uses —
every mode's frequency, damping, order, branch and flags, the model's parameters and
errors, the diagnosis — to 0.1 % (a damping ratio to 0.5 %: the same tenth of what the
stabilization takes for one pole, session 35), the arrays' shapes and types. Measured: a
digest written on an AMD EPYC and a run on an Intel Xeon with AVX-512 (OpenBLAS's SkylakeX
kernels; numpy 2.4.6, scipy 1.17.1) differ beyond 1e-5 in 19 places, by near-tie decisions
of the stabilization diagram (14,226 against 14,250 poles) that move a weak mode's shape
statistics (mode 42, 2.3 % of the response: MPC 0.994 against 0.9995, branch confidence
0.90 against 0.99) and the sums of the arrays that hold them; at the portable level they
agree. ``--write`` replaces the digest of the running numerics and keeps the others; a
change of behaviour makes the others stale, and they are removed in the same commit (session
33: the EPYC digest went with the band-top refinement; a machine with no digest of its own
is compared at the portable level with the ones left).

Tolerances: 1e-5 relative on numbers and on the sums of single-precision arrays (a
different BLAS or CPU changes the last digits of an optimiser's answer, and more of an
ill-conditioned one: the standard error of a parameter the modes hardly determine moved by
2.8e-6 between two machines of the same kind). Left out besides (``MACHINE_NOISE``): a
cluster's representative order (the member nearest the cluster's median, an argmin among
members whose scores tie to ~1e-13) and the rejected poles (poles near the noise, which
the stabilization drops: their frequencies moved by up to 0.3 % and their damping by 27 %
between those two machines). And the standard error and t of a fitted parameter its data
do not determine (|t| < 1: its error exceeds its value — the inverse of a near-singular
information matrix) or determine beyond the fit's own precision (|t| > 1e6: an error under a
millionth of the value, below what the forward-difference Jacobian of a least-squares
solver stopping at a relative tolerance of 1e-8 resolves, e.g. a parameter held on its
vanishing floor of 1e-12), judged by the stored t (:func:`_ill_conditioned`): between two
machine kinds (session 26) a rejected candidate's undetermined rim mass (t = 2e-5) moved by
2.6e-5 and a Timoshenko c_s on its floor (t = 4.5e7) by 4 %, every other number within 1e-5.
"""

from __future__ import annotations

import csv
import json
import sys
from pathlib import Path

import h5py
import numpy as np
import pytest

from tiremodal_cli.modal.stabilization import StabilizationOptions

ROOT = Path(__file__).resolve().parents[1]
SAMPLE = ROOT / "sample_data" / "gl073a_sim.h5"
DIGEST = ROOT / "tests" / "data" / "sample_run_digest.json"

#: keys whose values differ between two identical runs (time, place, checksums of files)
VOLATILE = {"seconds", "provenance", "created_utc", "created", "tiremodal_version", "version", "git_commit",
            "command", "python", "numpy", "scipy", "platform", "input_file", "measurement", "path",
            "input_sha256", "sha256", "outputs", "host", "user"}
#: values that move with the machine's floating point (module docstring)
MACHINE_NOISE = {"representative_order", "rejected"}


def _leaves(obj, prefix=""):
    """Flatten JSON into {path: number | string | bool | None}, volatile keys left out."""
    out = {}
    if isinstance(obj, dict):
        for k, v in obj.items():
            if k not in VOLATILE | MACHINE_NOISE:
                out.update(_leaves(v, f"{prefix}/{k}"))
    elif isinstance(obj, list):
        for i, v in enumerate(obj):
            out.update(_leaves(v, f"{prefix}[{i}]"))
    else:
        out[prefix] = obj
    return out


def _h5_digest(path):
    out = {}

    def attrs(name, obj):
        for k, v in obj.attrs.items():
            if k in VOLATILE | MACHINE_NOISE:
                continue
            v = v.decode() if isinstance(v, bytes) else v
            v = v.tolist() if isinstance(v, np.ndarray) else v.item() if isinstance(v, np.generic) else v
            out[f"{name}@{k}"] = v

    def visit(name, obj):
        attrs(name, obj)
        if isinstance(obj, h5py.Dataset):
            a = obj[()]
            if a.dtype.kind in "SOU":
                out[name] = {"shape": list(a.shape), "dtype": "str",
                             "values": [x.decode() if isinstance(x, bytes) else str(x) for x in np.ravel(a)]}
                return
            x = np.asarray(a, dtype=np.complex128 if a.dtype.kind == "c" else np.float64).ravel()
            finite = np.isfinite(x)
            xf = np.where(finite, x, 0)
            ramp = np.linspace(1.0, 2.0, x.size) if x.size else x.real
            out[name] = {"shape": list(a.shape), "dtype": str(a.dtype), "n_nonfinite": int((~finite).sum()),
                         "sum": [float(np.sum(xf).real), float(np.sum(xf).imag)],
                         "sum_abs": float(np.sum(np.abs(xf))),
                         "ramp": [float(np.sum(ramp * xf).real), float(np.sum(ramp * xf).imag)]}

    with h5py.File(path, "r") as f:
        attrs("/", f)
        f.visititems(visit)
    return out


def _csv_digest(path):
    with open(path, newline="") as fh:
        rows = list(csv.DictReader(fh))
    return {f"[{i}]/{k}": v for i, r in enumerate(rows) for k, v in r.items()}


def digest(outdir) -> dict:
    """The digest of one run folder."""
    outdir = Path(outdir)
    d = {}
    for name in ("identify.json", "diagnosis.json", "sensitivity.json"):
        d[name] = _leaves(json.loads((outdir / name).read_text()))
    d["run.json"] = _leaves(json.loads((outdir / "run.json").read_text())["summary"])
    d["modes.csv"] = _csv_digest(outdir / "modes.csv")
    for name in ("frf.h5", "modal.h5"):
        d[name] = _h5_digest(outdir / name)
    return d


def _sample_run(outdir):
    from tiremodal_cli.workflow.pipeline import run

    run(SAMPLE, outdir)
    return digest(outdir)


def _drop_noise(obj):
    """A JSON value without its :data:`MACHINE_NOISE` keys, at any depth."""
    if isinstance(obj, dict):
        return {k: _drop_noise(v) for k, v in obj.items() if k not in MACHINE_NOISE}
    if isinstance(obj, list):
        return [_drop_noise(v) for v in obj]
    return obj


def _close(a, b, rtol):
    if isinstance(a, bool) or isinstance(b, bool) or a is None or b is None:
        return a == b
    if isinstance(a, (int, float)) and isinstance(b, (int, float)):
        if isinstance(a, float) and isinstance(b, float) and np.isnan(a) and np.isnan(b):
            return True
        return bool(np.isclose(a, b, rtol=rtol, atol=1e-12))
    if isinstance(a, str) and isinstance(b, str):
        if a == b:
            return True
        if a[:1] in "{[" and b[:1] in "{[":  # a JSON attribute: its numbers to the same tolerance
            try:
                ja, jb = _drop_noise(json.loads(a)), _drop_noise(json.loads(b))
                return _close(ja, jb, rtol)
            except ValueError:
                return a == b
        try:
            return bool(np.isclose(float(a), float(b), rtol=rtol, atol=1e-12))
        except ValueError:
            return a == b
    if isinstance(a, list) and isinstance(b, list):
        return len(a) == len(b) and all(_close(x, y, rtol) for x, y in zip(a, b))
    if isinstance(a, dict) and isinstance(b, dict):
        return a.keys() == b.keys() and all(_close(a[k], b[k], rtol) for k in a)
    return a == b


#: |t| outside [T_UNDETERMINED, T_BEYOND_PRECISION]: a parameter's standard error and t are
#: machine noise (module docstring)
T_UNDETERMINED, T_BEYOND_PRECISION = 1.0, 1e6


def _ill_conditioned(key: str, stored: dict) -> bool:
    """Whether ``key`` is the standard error or t of a fitted parameter whose stored t lies
    outside [:data:`T_UNDETERMINED`, :data:`T_BEYOND_PRECISION`] (or is null)."""
    head, _, leaf = key.rpartition("/")
    if leaf not in ("std_error", "t") or "/parameters/" not in head:
        return False
    t = stored.get(f"{head}/t")
    return t is None or not T_UNDETERMINED <= abs(t) <= T_BEYOND_PRECISION


def differences(got: dict, want: dict, rtol: float = 1e-5, field_rtol: dict | None = None) -> list[str]:
    """Human-readable differences between two digests (empty when they agree); ``field_rtol``:
    {leaf name: its own relative tolerance}."""
    out = []
    field_rtol = field_rtol or {}
    for f in sorted(set(got) | set(want)):
        g, w = got.get(f, {}), want.get(f, {})
        for k in sorted(set(g) | set(w)):
            if k not in g or k not in w:
                out.append(f"{f} {k}: {'missing now' if k not in g else 'new'}")
            elif _ill_conditioned(k, w):
                continue
            elif not _close(g[k], w[k], field_rtol.get(k.rsplit("/", 1)[-1], rtol)):
                out.append(f"{f} {k}: {str(g[k])[:120]} != stored {str(w[k])[:120]}")
    return out


def numerics() -> str:
    """The numerics a run's last digits and near-tie decisions depend on: numpy's and scipy's
    versions and the BLAS libraries loaded (implementation, version, the CPU kernels chosen)."""
    import scipy
    import scipy.linalg  # noqa: F401  (loads scipy's BLAS)
    from threadpoolctl import threadpool_info

    blas = sorted({f"{d.get('internal_api')} {d.get('version')} {d.get('architecture')}"
                   for d in threadpool_info() if d.get("user_api") == "blas"})
    return f"numpy {np.__version__}, scipy {scipy.__version__}, blas: " + "; ".join(blas)


#: the portable level (module docstring): fields left out, as near-tie statistics of weak
#: modes (their shape's phase collinearity, the confidences read from it, their share of the
#: response: a 2.3 %-significant mode's moved by 8e-4 relative between the two machines)
NEAR_TIE = {"mpc", "branch_confidence", "n_confidence", "significance"}
#: the portable level's relative tolerance
PORTABLE_RTOL = 1e-3
#: and a damping ratio's: the same tenth of what the stabilization takes for one pole
#: (``tol_damping`` 5 % against ``tol_freq`` 1 %: 0.5 %). Session 35: between an AMD EPYC
#: (OpenBLAS Haswell kernels) and an Intel Xeon (SkylakeX) the weak mode 42's damping differs
#: by 0.31 % (0.037658 against 0.037540), every frequency within 0.1 %
PORTABLE_DAMPING_RTOL = PORTABLE_RTOL * StabilizationOptions().tol_damping / StabilizationOptions().tol_freq


def portable(d: dict) -> dict:
    """A digest at the portable level (module docstring): the JSON and table leaves but the
    :data:`NEAR_TIE` fields, and of the HDF5 files each dataset's shape and type only, but the
    stabilization diagram's (its pole count is a near-tie count) and no attributes."""
    out = {}
    for f, leaves in d.items():
        if f.endswith(".h5"):
            out[f] = {k: {"shape": v["shape"], "dtype": v["dtype"]} for k, v in leaves.items()
                      if "@" not in k and isinstance(v, dict) and "shape" in v and not k.endswith("diagram")}
        else:
            out[f] = {k: v for k, v in leaves.items() if k.rsplit("/", 1)[-1] not in NEAR_TIE}
    return out


def stored_digests() -> dict:
    """{numerics: digest} as stored."""
    return json.loads(DIGEST.read_text())


def check_digest(got: dict, key: str, stored: dict) -> list[str]:
    """Differences of a run's digest ``got`` on numerics ``key`` from the stored ones: every
    number against its own numerics' digest, else the portable level against every one."""
    if key in stored:
        return differences(got, stored[key])
    return [f"(portable, against {k}) {d}" for k, want in stored.items()
            for d in differences(portable(got), portable(want), PORTABLE_RTOL,
                                 {"damping_ratio": PORTABLE_DAMPING_RTOL})]


def test_sample_run_matches_the_stored_digest(tmp_path):
    got = _sample_run(tmp_path / "run")
    diff = check_digest(got, numerics(), stored_digests())
    assert not diff, f"{len(diff)} differences from {DIGEST.name}:\n" + "\n".join(diff[:40])


def test_the_portable_level_sees_a_moved_mode_but_not_a_near_tie():
    """At the portable level a weak mode's MPC moved by 0.5 % is no difference, nor its damping
    moved by 0.31 % (the two machine kinds' mode 42); its frequency moved by 0.2 % is one, its
    damping moved by 1 % is one, and so is a dataset's changed shape."""
    want = {"modes.csv": {"[4]/frequency_hz": "100.0", "[4]/mpc": "0.994", "[4]/damping_ratio": "0.037540"},
            "modal.h5": {"shapes": {"shape": [48, 3, 34], "dtype": "complex128", "sum": [1.0, 0.0]}}}
    got = json.loads(json.dumps(want))
    got["modes.csv"]["[4]/mpc"] = "0.9995"
    got["modes.csv"]["[4]/damping_ratio"] = "0.037658"
    got["modal.h5"]["shapes"]["sum"] = [1.1, 0.0]
    assert check_digest(got, "here", {"there": want}) == []
    got["modes.csv"]["[4]/frequency_hz"] = "100.2"
    got["modal.h5"]["shapes"]["shape"] = [47, 3, 34]
    assert len(check_digest(got, "here", {"there": want})) == 2
    got["modes.csv"]["[4]/damping_ratio"] = "0.03792"
    assert len(check_digest(got, "here", {"there": want})) == 3
    assert len(check_digest(got, "there", {"there": want})) == 4  # its own numerics: every number (the dataset one leaf)


def test_the_digest_sees_a_changed_number(tmp_path):
    """The comparison can fail: one number moved by 1e-4 relative (ten times the tolerance) is a difference."""
    want = next(iter(stored_digests().values()))
    got = json.loads(json.dumps(want))
    key = next(k for k, v in got["identify.json"].items() if isinstance(v, float) and v != 0)
    got["identify.json"][key] *= 1 + 1e-4
    assert differences(got, want) == [f"identify.json {key}: {got['identify.json'][key]} "
                                      f"!= stored {want['identify.json'][key]}"]


def test_an_ill_conditioned_parameters_statistics_are_machine_noise():
    """The standard error and t of a parameter the data leave undetermined (|t| < 1) or pin
    beyond the fit's precision (|t| > 1e6) are not compared; a well-determined one's are, and
    every parameter's value is."""
    want = {"d.json": {"/c[0]/parameters/a/value": 1.0, "/c[0]/parameters/a/std_error": 5e4,
                       "/c[0]/parameters/a/t": 2e-5, "/c[0]/parameters/b/value": 1e-12,
                       "/c[0]/parameters/b/std_error": 2e-20, "/c[0]/parameters/b/t": 4.5e7,
                       "/c[0]/parameters/c/value": 3.0, "/c[0]/parameters/c/std_error": 0.1,
                       "/c[0]/parameters/c/t": 30.0}}
    got = json.loads(json.dumps(want))
    for k in ("a/std_error", "a/t", "b/std_error", "b/t"):
        got["d.json"][f"/c[0]/parameters/{k}"] *= 1.04
    assert differences(got, want) == []
    got["d.json"]["/c[0]/parameters/c/std_error"] *= 1 + 1e-4
    got["d.json"]["/c[0]/parameters/a/value"] *= 1 + 1e-4
    assert len(differences(got, want)) == 2


def test_json_attributes_are_compared_number_by_number():
    """A JSON attribute (modal.h5's meta) differing in the 10th digit is the same; in the 5th, not."""
    assert _close('{"f": [1.0, "x"]}', '{"f": [1.0000000001, "x"]}', 1e-6)
    assert not _close('{"f": [1.0, "x"]}', '{"f": [1.00001, "x"]}', 1e-6)
    assert not _close('{"f": [1.0, "x"]}', '{"f": [1.0, "y"]}', 1e-6)


if __name__ == "__main__":
    if sys.argv[1:] != ["--write"]:
        sys.exit("usage: python tests/test_digest.py --write")
    import tempfile

    with tempfile.TemporaryDirectory() as tmp:
        run_digest = _sample_run(Path(tmp) / "run")
    here = numerics()
    DIGEST.write_text(json.dumps({**stored_digests(), here: run_digest}, indent=0, sort_keys=True) + "\n")
    print(f"wrote {DIGEST} for {here}")
