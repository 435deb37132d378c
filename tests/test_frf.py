"""The FRF stage: estimators, windows, hit-quality checks, file and UFF output, bad input."""

import json

import h5py
import numpy as np
import pytest
import pyuff
import scipy.optimize
from numpy.testing import assert_allclose

from tiremodal_cli.frf.estimate import FRFOptions, compute_frf, estimate
from tiremodal_cli.io.frffile import read_frf
from tiremodal_cli.io.measurement import Measurement, write_measurement
from tiremodal_cli.tyre.simulate import Faults, SimulationConfig, half_sine_spectrum, simulate
from tiremodal_cli.frf.windows import correct_damping, exponential_window

from conftest import run_cli


def test_estimators_agree_without_noise_and_bracket_with_it(rng):
    H = np.exp(1j * np.linspace(0, 3, 50)) * np.linspace(1, 2, 50)
    F = rng.standard_normal((20, 50)) + 1j * rng.standard_normal((20, 50))
    for est in ("H1", "H2", "Hv"):
        got, coh = estimate(F, H * F, estimator=est)
        assert_allclose(got, H, rtol=1e-12)
        assert_allclose(coh, 1.0, rtol=1e-12)
    N = 0.5 * (rng.standard_normal((20, 50)) + 1j * rng.standard_normal((20, 50)))
    h1, _ = estimate(F, H * F + N, estimator="H1")
    h2, _ = estimate(F, H * F + N, estimator="H2")
    hv, _ = estimate(F, H * F + N, estimator="Hv")
    # |H1| ≤ |Hv| ≤ |H2| always (Bendat & Piersol)
    assert np.all(np.abs(h1) <= np.abs(hv) + 1e-12) and np.all(np.abs(hv) <= np.abs(h2) + 1e-12)


def test_noisy_h1_within_coherence_error_bound(noisy_sim):
    """|H1 − H| / |H| is the random error the coherence predicts: √((1 − γ²) / (n γ²)).

    (Bendat & Piersol, eq. 9.90, for the complex error with n averages.) Tread and
    sidewall channels, lines with γ² > 0.8; the rim channel has true zeros at its nodes.
    """
    r = compute_frf(noisy_sim.measurement, FRFOptions(band_hz=(20, 400)))
    true = noisy_sim.frf[..., (noisy_sim.freq_hz >= 20) & (noisy_sim.freq_hz <= 400)]
    g = r.coherence[:2]
    err = np.abs(r.H[:2] - true[:2]) / np.abs(true[:2])
    bound = np.sqrt((1 - g) / (r.n_averages[None, :, None] * g))
    q = (err / bound)[g > 0.8]
    assert q.size > 5000
    assert 0.7 < np.median(q) < 1.4
    assert np.percentile(q, 95) < 4.0
    assert np.median(err[g > 0.8]) < 0.02


def test_every_fault_rejected_and_no_clean_hit():
    faults = Faults(double_hits=((1, 0), (9, 2), (20, 1), (33, 2)),
                    clipped=((2, 1, "tread"), (5, 0, "sidewall"), (14, 2, "force"), (27, 0, "rim")))
    for seed in (11, 12):
        s = simulate(SimulationConfig(n_points=34, n_hits=3, n_samples=2048, noise=0.01, seed=seed,
                                      params=s_params(), faults=faults))
        r = compute_frf(s.measurement)
        got = {(x.point, x.hit) for x in r.rejections}
        want = {(p, h) for p, h in faults.double_hits} | {(p, h) for p, h, _ in faults.clipped}
        assert got == want, (seed, sorted(got ^ want))
        reasons = {(x.point, x.hit): x.reason for x in r.rejections}
        assert all(reasons[(p, h)] == "double hit" for p, h in faults.double_hits)
        assert reasons[(14, 2)] == "clipped (overloaded) force"
        assert reasons[(2, 1)] == "clipped (overloaded) response"
        assert r.n_averages.sum() == 34 * 3 - len(want)


def s_params():
    from tiremodal_cli.tyre.model import TyreParameters

    return TyreParameters(m_w=1000.0)


def test_dead_channel_flagged_not_fatal():
    s = simulate(SimulationConfig(n_points=10, n_hits=2, n_samples=1024, noise=0.01, seed=3, params=s_params(),
                                  faults=Faults(dead_channel="sidewall")))
    r = compute_frf(s.measurement)
    assert r.dead_channels == ("sidewall",)
    assert np.all(np.isnan(r.H[1])) and np.all(np.isfinite(r.H[0]))
    assert all(x.hit is None for x in r.rejections)


def test_inconsistent_hit_rejected_by_frf_mac(noisy_sim):
    m = noisy_sim.measurement
    resp = np.array(m.response)
    resp[4, 1, 0] = np.roll(resp[4, 1, 0], 37) * -1.0  # a record that does not belong to its force
    bad = Measurement(force=m.force, response=resp, sample_rate=m.sample_rate, point_angle=m.point_angle,
                      channel_name=m.channel_name, channel_location=m.channel_location,
                      channel_angle=m.channel_angle)
    r = compute_frf(bad)
    assert [(x.point, x.hit) for x in r.rejections] == [(4, 1)]
    assert "poor consistency" in r.rejections[0].reason and r.rejections[0].channel == "tread"
    # the same test untouched: nothing rejected (the rim channel at its nodes is noise, not a bad hit)
    assert compute_frf(noisy_sim.measurement).rejections == ()


def _sdof_records(fn, zeta, fs, n, n_hits=2, seed=0):
    """Impact records of a single-DOF oscillator (accelerance), built on the DFT grid."""
    rng = np.random.default_rng(seed)
    f = np.fft.rfftfreq(n, 1 / fs)
    w, wn = 2 * np.pi * f, 2 * np.pi * fn
    H = -(w**2) / (wn**2 - w**2 + 2j * zeta * wn * w)
    F = np.stack([half_sine_spectrum(f, 1e-3, 100 * (1 + 0.1 * rng.uniform(-1, 1))) * np.exp(-2j * np.pi * f * 0.01)
                  for _ in range(n_hits)]) * fs
    return np.fft.irfft(F, n), np.fft.irfft(F * H, n)[:, None, :]


def _fit_sdof(freq, H, f0):
    """Local least-squares fit of an SDOF accelerance plus a constant residual (scipy.optimize)."""
    sel = np.abs(freq - f0) < 0.15 * f0

    def res(x):
        fn, z, a, b, c, d = x
        w, wn = 2 * np.pi * freq[sel], 2 * np.pi * fn
        model = (a + 1j * b) * -(w**2) / (wn**2 - w**2 + 2j * z * wn * w) + c + 1j * d
        r = model - H[sel]
        return np.concatenate([r.real, r.imag])

    sol = scipy.optimize.least_squares(res, [f0, 0.02, 1.0, 0.0, 0.0, 0.0], x_scale="jac")
    return sol.x[0], sol.x[1]


def test_exponential_window_correction_recovers_damping():
    fn, zeta, fs, n = 80.0, 0.01, 1024.0, 8192
    force, resp = _sdof_records(fn, zeta, fs, n)
    # a window that doubles the apparent damping: 1/τ = ζ ω_n
    tau = 1 / (zeta * 2 * np.pi * fn)
    m = Measurement(force=force[:, None, :].transpose(1, 0, 2), response=resp[None], sample_rate=fs,
                    point_angle=np.zeros(1), channel_name=("a",), channel_location=("tread",),
                    channel_angle=np.zeros(1))
    r = compute_frf(m, FRFOptions(exp_tau_s=tau, force_window=False))
    f_est, z_est = _fit_sdof(r.freq_hz, r.H[0, 0], fn)
    assert z_est == pytest.approx(2 * zeta, rel=0.05)  # the window did double it
    f_cor, z_cor = correct_damping(f_est, z_est, r.exp_tau_s)
    assert z_cor == pytest.approx(zeta, rel=0.02)
    assert f_cor == pytest.approx(fn, rel=1e-4)
    _, tau2 = exponential_window(n, fs, end_value=0.01)
    assert tau2 == pytest.approx(-(n - 1) / fs / np.log(0.01))


def test_cli_frf_file_uff_plot(tmp_path, noisy_sim):
    meas = tmp_path / "m.h5"
    write_measurement(meas, noisy_sim.measurement)
    before = meas.read_bytes()
    out, uff, png = tmp_path / "f.h5", tmp_path / "f.uff", tmp_path / "f.png"
    res = run_cli(["frf", meas, "-o", out, "--band", 0, 300, "--uff", uff, "--plot", png, "--plot-points", "1,3",
                   "--exp-end", 0.1, "--json"])
    assert res.exit_code == 0, res.output
    d = json.loads(res.stdout)
    assert d["n_points"] == 12 and d["band_hz"] == [0.0, 300.0] and d["exponential_window"]["tau_s"] > 0
    r = read_frf(out)
    assert r.H.shape == (3, 12, d["n_freq"]) and r.exp_tau_s == pytest.approx(d["exp_tau_s"])
    with h5py.File(out) as h:
        assert len(h.attrs["input_sha256"]) == 64
    assert meas.read_bytes() == before
    sets = pyuff.UFF(str(uff)).read_sets()
    assert [s["type"] for s in sets[:1]] == [15]  # the points' and sensors' geometry first
    sets = [s for s in sets if s["type"] == 58]
    assert len(sets) == 2 * 3 * 12  # an FRF and its coherence for every channel and point
    assert sorted({s["func_type"] for s in sets}) == [4, 9]
    for s in sets:
        ic, ip = s["rsp_node"] - 1, s["ref_node"] - 101
        assert_allclose(s["x"], r.freq_hz, rtol=1e-5, atol=1e-6)
        want = r.H[ic, ip] if s["func_type"] == 4 else r.coherence[ic, ip]
        assert_allclose(s["data"], want, rtol=1e-9, atol=1e-9 * np.abs(want).max())
        assert s["id1"].startswith("tiremodal ") and s["id3"] != "NONE" and s["id4"] == "NONE"
        assert s["id5"] == f"averages {int(r.n_averages[ip])}"
    assert png.stat().st_size > 10_000 and png.read_bytes()[:4] == b"\x89PNG"


def _meas(force, response):
    n_c = response.shape[2]
    return Measurement(force=force, response=response, sample_rate=1000.0,
                       point_angle=np.linspace(0, 2 * np.pi, force.shape[0], endpoint=False),
                       channel_name=tuple(f"c{i}" for i in range(n_c)), channel_location=("tread",) * n_c,
                       channel_angle=np.zeros(n_c))


@pytest.mark.parametrize("case, msg", [
    ("band", r"band 0–900 Hz is outside the data \(0–500 Hz\)"),
    ("zero force", r"every hit of every point was rejected \(zero force"),
    ("nan", r"every hit of every point was rejected \(non-finite force samples\)"),
    ("layout", "is not a measurement"),
])
def test_cli_frf_bad_input(tmp_path, case, msg, noisy_sim):
    p = tmp_path / "m.h5"
    s = simulate(SimulationConfig(n_points=8, n_hits=2, n_samples=512, sample_rate=1000.0, seed=1, params=s_params()))
    f, y = np.array(s.measurement.force), np.array(s.measurement.response)
    args = []
    if case == "band":
        args = ["--band", 0, 900]
    if case == "zero force":
        f[:] = 0
    if case == "nan":
        f[:, :, 10] = np.nan
    write_measurement(p, _meas(f, y))
    if case == "layout":
        run_cli(["frf", p, "-o", tmp_path / "first.h5"])
        p = tmp_path / "first.h5"
    before = p.read_bytes()
    res = run_cli(["frf", p, "-o", tmp_path / "out.h5", *args])
    assert res.exit_code == 2
    lines = res.stderr.strip().splitlines()
    assert len(lines) == 1 and __import__("re").search(msg, lines[0]), lines
    assert p.read_bytes() == before and not (tmp_path / "out.h5").exists()


def test_nan_in_one_hit_rejects_that_hit(tmp_path):
    s = simulate(SimulationConfig(n_points=8, n_hits=3, n_samples=512, sample_rate=1000.0, seed=1, params=s_params()))
    y = np.array(s.measurement.response)
    y[2, 1, 0, 100] = np.nan
    r = compute_frf(_meas(np.array(s.measurement.force), y))
    assert [(x.point, x.hit, x.channel, x.reason) for x in r.rejections] == \
        [(2, 1, "c0", "non-finite response samples")]
    assert np.all(np.isfinite(r.H))


def test_forms_are_consistent(exact_sim):
    m = exact_sim.measurement
    acc = compute_frf(m, FRFOptions(force_window=False))
    mob = compute_frf(m, FRFOptions(force_window=False, form="mobility"))
    rec = compute_frf(m, FRFOptions(force_window=False, form="receptance"))
    assert acc.freq_hz[0] == 0 and mob.freq_hz[0] > 0
    w = 2 * np.pi * mob.freq_hz
    assert_allclose(mob.H * 1j * w, acc.H[..., 1:], rtol=1e-12)
    assert_allclose(rec.H * -(w**2), acc.H[..., 1:], rtol=1e-12)


def test_uff_export_names_a_dead_channel(tmp_path, exact_sim, caplog):
    """A dead channel is left out of the UFF export, with a warning naming it."""
    import dataclasses
    import logging

    from tiremodal_cli.frf.estimate import FRFOptions, compute_frf
    from tiremodal_cli.io.frfuff import write_frf_uff

    r = compute_frf(exact_sim.measurement, FRFOptions(band_hz=(0.0, 300.0)))
    r = dataclasses.replace(r, dead_channels=("rim",))
    with caplog.at_level(logging.WARNING):
        write_frf_uff(tmp_path / "f.uff", r, test_name="tyre A")
    assert any("'rim'" in m and "dead" in m for m in caplog.messages)
    sets = [s for s in pyuff.UFF(str(tmp_path / "f.uff")).read_sets() if s["type"] == 58]
    assert {s["rsp_ent_name"].strip() for s in sets} == {"tread", "sidewall"}
    assert all(s["id4"] == "tyre A" for s in sets)


def test_force_autospectrum_is_the_half_sine_pulse_spectrum(tmp_path):
    """A half-sine pulse of A = 150 N and w = 2 ms sampled at 10 kHz: the FRF stage's force
    autospectrum is |fs · F(ω)|² with the pulse's Fourier transform written out here,
    |F(ω)| = 2 A π w |cos(ωw/2)| / |π² − ω²w²| (to 1 % below half its first zero at 1.5 / w,
    where the sampled pulse's aliasing is negligible); it survives the FRF file."""
    fs, n, w, amp = 10_000.0, 4096, 2e-3, 150.0
    t = np.arange(n) / fs - 0.01
    pulse = np.where((t >= 0) & (t <= w), amp * np.sin(np.pi * np.clip(t, 0, w) / w), 0.0)
    rng = np.random.default_rng(3)
    force = np.stack([pulse, pulse])[None]  # (1 point, 2 hits, n)
    resp = np.stack([np.convolve(pulse, rng.standard_normal(64) * np.exp(-np.arange(64) / 8))[:n]] * 2)[None, :, None]
    m = Measurement(force=force, response=resp, sample_rate=fs, point_angle=np.zeros(1),
                    channel_name=("c0",), channel_location=("tread",), channel_angle=np.zeros(1))
    r = compute_frf(m, FRFOptions(band_hz=(0.0, 2000.0)))
    om = 2 * np.pi * r.freq_hz
    want = (fs * 2 * amp * np.pi * w * np.abs(np.cos(om * w / 2)) / np.abs(np.pi**2 - (om * w) ** 2)) ** 2
    sel = (r.freq_hz > 0) & (r.freq_hz < 0.75 / w)
    assert r.force_autospectrum.shape == (1, r.freq_hz.size)
    assert_allclose(r.force_autospectrum[0, sel], want[sel], rtol=0.01)
    from tiremodal_cli.io.frffile import write_frf
    back = read_frf(write_frf(tmp_path / "f.h5", r))
    assert_allclose(back.force_autospectrum, r.force_autospectrum, rtol=0, atol=0)


def test_a_point_whose_only_hit_bounced_keeps_an_unbiased_frf():
    """One hit per point, two points' hits bounced (a second blow 0.35–0.7 of the first,
    3–8 ms later: the simulator's double hit). A linear structure's H1 = Y / F holds for
    any force the window keeps whole, so those points are used — their H within the noise
    of the generator's FRF like any clean point — and each is reported with the delay the
    generator drew (to a sample). Cut at the first blow, as a single hit's window would be,
    the same record's FRF is off by the second blow's share (tens of per cent): the window
    over both blows is what makes the point usable."""
    import scipy.fft

    from tiremodal_cli.frf.windows import force_window

    s = simulate(SimulationConfig(n_points=12, n_hits=1, n_samples=2048, noise=0.005, seed=21, params=s_params(),
                                  faults=Faults(double_hits=((2, 0), (7, 0)))))
    band = (20.0, 400.0)
    r = compute_frf(s.measurement, FRFOptions(band_hz=band))
    assert r.meta["failed_points"] == [] and list(r.point_index) == list(range(12))
    assert not r.rejections
    used = {u["point"]: u for u in r.meta["double_hits_used"]}
    drawn = {h["point"]: h["double_hit"] for h in s.truth["hits"] if "double_hit" in h}
    assert sorted(used) == sorted(drawn) == [2, 7]
    fs = s.measurement.sample_rate
    for p in used:
        assert used[p]["delay_s"] == pytest.approx(drawn[p]["delay_s"], abs=1.5 / fs)
        assert -20 < used[p]["notch_db"] < 0
    sel = (s.freq_hz >= band[0]) & (s.freq_hz <= band[1])
    true = s.frf[:2][..., sel]
    err = np.median(np.abs(r.H[:2] - true) / np.abs(true), axis=(0, 2))  # per point
    clean = np.median(np.delete(err, [2, 7]))
    assert err[2] < 3 * clean and err[7] < 3 * clean, (err, clean)
    # the control: the bounced record with the window of its first blow alone
    f = np.asarray(s.measurement.force[2, 0], float)
    y = np.asarray(s.measurement.response[2, 0, 0], float)
    ipk = int(np.argmax(np.abs(f)))
    first = force_window(f[None], fs, length_s=0.5 * used[2]["delay_s"],
                         extent=(np.array([ipk - 1]), np.array([ipk + 1])))[0]
    Fw, Y = scipy.fft.rfft(f * first), scipy.fft.rfft(y)
    cut = np.median(np.abs(Y[sel] / Fw[sel] - s.frf[0, 2, sel]) / np.abs(s.frf[0, 2, sel]))
    assert cut > 10 * err[2], (cut, err[2])


@pytest.mark.parametrize("size, used", [(0.5, True), (0.95, False)])
def test_a_bounce_is_used_only_while_its_notch_is_within_the_force_rule(size, used):
    """A second blow of relative size a after Δt notches the force spectrum to |1 − a|:
    −6 dB for a = 0.5 (used), −26 dB for a = 0.95 (beyond the hammer-test rule's 20 dB:
    the point stays out); the notch is read from the record, not assumed."""
    from tiremodal_cli.frf.hits import pulse_extent
    from tiremodal_cli.frf.screening import Rejection, bounced_only_hits

    fs, n = 2048.0, 2048
    t = np.arange(n) / fs
    w = 4e-3  # eight samples: both blows' peaks sampled

    def pulse(t0):
        return np.where((t >= t0) & (t < t0 + w), np.sin(np.pi * (t - t0) / w), 0.0)

    f = (pulse(0.01) + size * pulse(0.02))[None]
    ext = pulse_extent(f, fs)
    use, _, notes = bounced_only_hits(f, fs, [Rejection(0, 0, "double hit", "force")], 0, ext)
    assert bool(use.size) is used
    if used:
        assert notes[0]["notch_db"] == pytest.approx(20 * np.log10(1 - size), abs=1.0)
