"""The measurement file: round trip, and one clear line with exit 2 for each bad input."""

import hashlib

import h5py
import numpy as np
import pytest
from numpy.testing import assert_array_equal

from tiremodal_cli.errors import DataFormatError
from tiremodal_cli.io.measurement import Measurement, read_measurement, write_measurement

from conftest import run_cli


def small(n_p=8, n_h=2, n_c=3, n_s=256, seed=0):
    rng = np.random.default_rng(seed)
    return Measurement(force=rng.standard_normal((n_p, n_h, n_s)).astype(np.float32),
                       response=rng.standard_normal((n_p, n_h, n_c, n_s)).astype(np.float32),
                       sample_rate=1024.0, point_angle=np.linspace(0, 2 * np.pi, n_p, endpoint=False),
                       channel_name=("t", "s", "r")[:n_c], channel_location=("tread", "sidewall", "rim")[:n_c],
                       channel_angle=np.zeros(n_c), inflation_pressure=8e5, tire="test")


def test_round_trip(tmp_path):
    m = small()
    write_measurement(tmp_path / "m.h5", m)
    r = read_measurement(tmp_path / "m.h5")
    assert_array_equal(r.force, m.force)
    assert_array_equal(r.response, m.response)
    assert r.channel_location == m.channel_location and r.sample_rate == 1024.0 and r.tire == "test"
    with pytest.raises(FileExistsError, match="--overwrite"):
        write_measurement(tmp_path / "m.h5", m)


def digest(p):
    return hashlib.sha256(p.read_bytes()).hexdigest()


def _edit(path, fn):
    with h5py.File(path, "a") as h:
        fn(h)


BAD = {
    "missing dataset": (lambda h: h.__delitem__("force"), "dataset 'force' is missing"),
    "wrong shape": (lambda h: (h.__delitem__("force"), h.create_dataset("force", data=np.zeros((8, 256)))),
                    r"dataset 'force' has shape \(8, 256\)"),
    "mismatched sizes": (lambda h: (h.__delitem__("force"), h.create_dataset("force", data=np.zeros((7, 2, 256)))),
                         "sizes do not match"),
    "non-finite samples": (lambda h: h["response"].__setitem__((1, 0, 2, 5), np.nan),
                           r"non-finite samples \(first at index \(1, 0, 2, 5\)\)"),
    "unknown version": (lambda h: h.attrs.__setitem__("format_version", 2), "unknown format_version 2"),
    "missing format": (lambda h: h.attrs.__delitem__("format"), "attribute 'format' is missing"),
    "bad location": (lambda h: (h.__delitem__("channel_location"),
                                h.create_dataset("channel_location", data=["tread", "sidewall", "hub"],
                                                 dtype=h5py.string_dtype())), "'hub' is not allowed"),
    "integer samples": (lambda h: (h.__delitem__("force"), h.create_dataset("force", data=np.zeros((8, 2, 256), int))),
                        "dtype int64"),
}


@pytest.mark.parametrize("case", sorted(BAD))
def test_bad_file_one_line_exit_2_unchanged(tmp_path, case):
    fn, msg = BAD[case]
    p = tmp_path / "bad.h5"
    write_measurement(p, small())
    _edit(p, fn)
    before = digest(p)
    with pytest.raises(DataFormatError, match=msg):
        read_measurement(p)
    res = run_cli(["info", p])
    assert res.exit_code == 2
    err = res.stderr.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("Error: ") and "Traceback" not in res.output
    assert digest(p) == before


def test_truncated_and_foreign_files(tmp_path):
    p = tmp_path / "m.h5"
    write_measurement(p, small())
    trunc = tmp_path / "trunc.h5"
    trunc.write_bytes(p.read_bytes()[: p.stat().st_size // 2])
    text = tmp_path / "notes.h5"
    text.write_text("time,force\n0,1\n")
    for f in (trunc, text):
        before = digest(f)
        res = run_cli(["info", f])
        assert res.exit_code == 2
        (line,) = res.stderr.strip().splitlines()
        assert line.startswith(f"Error: {f}: not a readable HDF5 file (truncated, or another format); allowed: ")
        assert digest(f) == before
    res = run_cli(["info", tmp_path / "absent.h5"])
    assert res.exit_code == 2 and "no such file" in res.stderr


def test_truncated_records_caught_when_read_lazily(tmp_path):
    """A file cut inside the records still opens (header intact) but fails on reading them."""
    p = tmp_path / "m.h5"
    m = small(n_s=4096)
    write_measurement(p, m)
    data = p.read_bytes()
    cut = tmp_path / "cut.h5"
    cut.write_bytes(data[: int(len(data) * 0.9)])
    res = run_cli(["frf", cut, "-o", tmp_path / "x.frf.h5"])
    assert res.exit_code == 2 and len(res.stderr.strip().splitlines()) == 1
    assert not (tmp_path / "x.frf.h5").exists()
    assert not list(tmp_path.glob(".*.part"))
