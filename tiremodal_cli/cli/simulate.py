"""``tiremodal simulate``: a physics-true roving-hammer test and its truth file."""

from __future__ import annotations

import dataclasses
import math
import typing
from pathlib import Path

import click
import numpy as np

from tiremodal_cli.io.config import load_mapping
from tiremodal_cli.tyre.effects import EFFECTS
from tiremodal_cli.errors import ParameterError
from tiremodal_cli.io.files import atomic_path, check_overwrite, check_size, refuse_input_as_output, write_text_atomic
from tiremodal_cli.io.ingest.uff import write_uff_time
from tiremodal_cli.io.measurement import write_measurement
from tiremodal_cli.tyre.model import TyreParameters
from tiremodal_cli.tyre.ring import elements_for
from tiremodal_cli.tyre.ring_parameters import RING_VARIANTS, RingParameters
from tiremodal_cli.tyre.simulate import MODELS, Channel, Faults, SimulationConfig, simulate
from tiremodal_cli.cli.main import cli
from tiremodal_cli.cli.options import FiniteRange, Progress, dumps, echo_json, json_option, overwrite_option, parse_key_values, say

_TABLES = {"params", "effects", "faults", "channels", "ring"}
_SCALARS = {f.name for f in dataclasses.fields(SimulationConfig)} - _TABLES - {"model"} | {"model", "variant"}


def _pairs(values, n, what):
    out = []
    for v in values:
        parts = v.split(":")
        if len(parts) != n:
            raise click.BadParameter(f"{v!r} must have {n} fields separated by ':'", param_hint=what)
        try:
            out.append(tuple(int(x) for x in parts[:2]) + tuple(parts[2:]))
        except ValueError:
            raise click.BadParameter(f"{v!r}: point and hit must be integers", param_hint=what) from None
    return tuple(out)


def _effects(specs) -> dict:
    out = {}
    for spec in specs:
        name, _, rest = spec.partition(":")
        if name not in EFFECTS:
            raise click.BadParameter(f"unknown effect {name!r}; allowed: {', '.join(EFFECTS)}",
                                     param_hint="--effect")
        vals = parse_key_values([x for x in rest.split(",") if x], "--effect") if rest else {}
        try:
            out[name] = {k: float(v) for k, v in vals.items()}
        except ValueError:
            raise click.BadParameter(f"{spec!r}: values must be numbers", param_hint="--effect") from None
    return out


def _typed_scalars(scal: dict, where: str) -> dict:
    """The config file's scalars checked against SimulationConfig's field types: an int field
    takes an integer (not a bool), a float field a finite number, a str field text, a bool
    field true/false; None where the default is None (damping)."""
    hints = typing.get_type_hints(SimulationConfig)
    out = {}
    for k, v in scal.items():
        if k not in hints:  # not a field (the ring's variant): checked where it is used
            out[k] = v
            continue
        t = hints[k]
        args = typing.get_args(t)
        if type(None) in args and v is None:
            out[k] = None
            continue
        base = next((a for a in args if a is not type(None)), t)
        ok = {int: isinstance(v, int) and not isinstance(v, bool),
              float: isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v),
              str: isinstance(v, str), bool: isinstance(v, bool)}.get(base, True)
        if not ok:
            want = {int: "an integer", float: "a finite number", str: "text", bool: "true or false"}[base]
            raise ParameterError(f"{where}: {k} = {v!r} is not allowed; allowed: {want}")
        out[k] = float(v) if base is float else v
    return out


def estimate_bytes(cfg: SimulationConfig) -> float:
    """Upper estimate of the memory a simulation holds at once, bytes.

    The model's modes (dense shapes: (2 + 1) dofs × 2 harmonics per order, squared, float64),
    the FRFs of every channel and point (complex128) with the modal sum's per-mode terms over
    the frequency lines, and the records (force and responses, float64, with the noise and
    type-conversion copies: ×3).
    """
    n_f = cfg.n_samples // 2 + 1
    n_c = len(cfg.channels)
    if getattr(cfg, "model", "paper") == "ring":
        # the ring's mesh (refined for every order below 1.25 × Nyquist), ≤ 5 fields on 2 nodes
        # per element; its condensed dense matrices and eigensolver workspace: 3 of n_dof²
        ne = max(cfg.ring.n_elements, elements_for(cfg.ring, 0.625 * cfg.sample_rate))
        n_dof = 10.0 * ne
        n_modes = n_dof
        shapes = 24.0 * n_dof**2
    else:
        n_modes = 6.0 * (cfg.n_max + 1)
        shapes = 12.0 * n_modes**2  # the shapes and the eigensolver's workspace (measured: n_max 1000 → 0.38 GiB)
    frfs = 16.0 * n_f * (n_c * cfg.n_points + n_modes)
    records = 3 * 8.0 * cfg.n_points * cfg.n_hits * (n_c + 1) * cfg.n_samples
    return shapes + frfs + records


def build_config(config_file, overrides: dict, params: dict, effects: dict, faults: dict) -> SimulationConfig:
    """Merge a TOML/JSON file with command-line values into a SimulationConfig.

    ``--param`` values go to the chosen model's parameters: ``[params]`` for the paper's
    model, ``[ring]`` for the finite-element ring (whose ``variant`` presets one physical
    effect, :data:`tiremodal_cli.tyre.ring.RING_VARIANTS`, under the explicit values).
    """
    data = load_mapping(config_file) if config_file else {}
    unknown = sorted(set(data) - _SCALARS - _TABLES)
    if unknown:
        raise ParameterError(f"{config_file}: unknown key {unknown[0]!r}; allowed: "
                             f"{', '.join(sorted(_SCALARS | _TABLES))}")
    scal = _typed_scalars({k: v for k, v in data.items() if k in _SCALARS}, str(config_file))
    scal.update({k: v for k, v in overrides.items() if v is not None})
    model = scal.pop("model", "paper")
    variant = scal.pop("variant", None)
    if model not in MODELS:
        raise ParameterError(f"model={model!r}; allowed: {', '.join(MODELS)}")
    if variant is not None and model != "ring":
        raise ParameterError(f"variant={variant!r} is a preset of the ring model; give model = \"ring\"")
    if variant is not None and variant not in RING_VARIANTS:
        raise ParameterError(f"variant={variant!r}; allowed: {', '.join(RING_VARIANTS)}")
    if model == "ring":
        if data.get("params") or data.get("effects") or effects:
            raise ParameterError("the ring model takes its parameters from [ring] (and --param), "
                                 "not [params] or effects")
        ring = RingParameters.from_mapping({**RING_VARIANTS.get(variant or "none", {}),
                                            **data.get("ring", {}), **params},
                                           where=str(config_file or "--param"))
        params = {}
    elif data.get("ring"):
        raise ParameterError(f"{config_file}: a [ring] table needs model = \"ring\"")
    p = TyreParameters.from_mapping({**data.get("params", {}), **params})
    eff = {**data.get("effects", {}), **effects}
    fd = {**data.get("faults", {}), **{k: v for k, v in faults.items() if v}}
    try:
        flt = Faults(double_hits=tuple(tuple(int(x) for x in v) for v in fd.get("double_hits", ())),
                     clipped=tuple((int(a), int(b), str(c)) for a, b, c in fd.get("clipped", ())),
                     dead_channel=fd.get("dead_channel"), missing_point=fd.get("missing_point"))
        chans = tuple(Channel(c["name"], c["location"], np.deg2rad(float(c.get("angle_deg", 0.0))))
                      for c in data.get("channels", ())) or SimulationConfig().channels
    except (TypeError, ValueError, KeyError) as exc:
        raise ParameterError(f"{config_file}: malformed faults or channels ({exc})") from None
    extra = {"model": model, "ring": ring} if model == "ring" else {}
    return SimulationConfig(params=p, effects=eff, faults=flt, channels=chans, **extra, **scal)


def mapping_toml(mapping: dict) -> str:
    """The UFF mapping as TOML (two flat tables; no TOML writer in the standard library)."""
    lines = ["# impact points: UFF reference node -> angle in degrees", "[points]"]
    lines += [f'"{k}" = {v!r}' for k, v in mapping["points"].items()]
    lines += ["", "# response channels: \"node:direction\" -> name, location, angle in degrees", "[channels]"]
    lines += [f'"{k}" = {{ name = "{c["name"]}", location = "{c["location"]}", angle_deg = {c["angle_deg"]!r} }}'
              for k, c in mapping["channels"].items()]
    return "\n".join(lines) + "\n"


@cli.command("simulate", epilog="\b\nExample:\n  tiremodal simulate ring.h5 --model ring --variant cavity --sample-rate 2048 --seed 1")
@click.argument("output", type=click.Path(dir_okay=False, path_type=Path))
@click.option("--config", "config_file", type=click.Path(exists=True, dir_okay=False),
              help="TOML/JSON file: scalars, [params], [effects.NAME], [faults], [[channels]].")
@click.option("--model", type=click.Choice(MODELS),
              help="Generator: 'paper' (the paper's model and its effects; default) or 'ring' "
                   "(the independent finite-element tyre, docs/simulate.md).")
@click.option("--variant", type=click.Choice(list(RING_VARIANTS)),
              help="Ring model: one physical effect switched on (default none).")
@click.option("--truth", type=click.Path(dir_okay=False, path_type=Path),
              help="Truth JSON (default: OUTPUT with suffix .truth.json).")
@click.option("--seed", type=int, help="Random seed (default 0).")
@click.option("--points", "n_points", type=click.IntRange(2),
              help="Impact points (default 34; with --hits, --samples and --n-max bounded by memory: "
                   "the estimate must fit a quarter of this machine's memory, at most 8 GiB).")
@click.option("--hits", "n_hits", type=click.IntRange(1, 100), help="Hits per point (default 3).")
@click.option("--sample-rate", type=FiniteRange(min=1, min_open=False), help="Hz (default 2048).")
@click.option("--samples", "n_samples", type=click.IntRange(64), help="Samples per record (default 4096; bounded by memory).")
@click.option("--noise", type=FiniteRange(0), help="Sensor noise, std relative to each record's RMS.")
@click.option("--damping", type=FiniteRange(0, 1, min_open=True, max_open=True),
              help="One modal damping ratio for all modes (default: the paper's, 1.6–3.8 %).")
@click.option("--n-max", type=click.IntRange(1), help="Highest circumferential order (default 30; bounded by memory).")
@click.option("--param", "params", multiple=True, metavar="NAME=VALUE",
              help="Parameter of the chosen model, e.g. k_r1=6.7e6 or m_w=clamped; for the ring "
                   "e.g. EA=1e8 or tangential=true (repeatable).")
@click.option("--effect", "effects", multiple=True, metavar="NAME[:P=V,...]",
              help=f"Switch on an extra effect: {', '.join(EFFECTS)} (repeatable).")
@click.option("--double-hit", multiple=True, metavar="POINT:HIT", help="Inject a double hit.")
@click.option("--clip", multiple=True, metavar="POINT:HIT:CHANNEL", help="Clip a record ('force' or a channel).")
@click.option("--dead-channel", help="Make this response channel dead.")
@click.option("--missing-point", type=int, help="Leave this point out of the file.")
@click.option("--dtype", type=click.Choice(["float32", "float64"]), help="Sample type (default float32).")
@click.option("--compress", is_flag=True, help="gzip the records (smaller, slower).")
@click.option("--uff-dir", type=click.Path(file_okay=False, path_type=Path),
              help="Also write the test as UFF 58 time records (one file a point) and mapping.toml there.")
@overwrite_option
@json_option
def simulate_cmd(output, config_file, model, variant, truth, seed, n_points, n_hits, sample_rate, n_samples, noise,
                 damping, n_max, params, effects, double_hit, clip, dead_channel, missing_point, dtype,
                 compress, uff_dir, overwrite, as_json):
    """Simulate a roving-hammer test of a tyre into OUTPUT (HDF5).

    The tyre is the paper's model (default) or, with --model ring, an independent
    finite-element tyre. Writes OUTPUT and a truth JSON beside it: every mode below Nyquist with n, branch,
    frequency, damping and shape, the parameters, effects and faults injected.
    """
    refuse_input_as_output({"OUTPUT": output, "--truth": truth or output.with_suffix(".truth.json"), "--uff-dir": uff_dir},
                           {"--config": config_file})
    overrides = dict(model=model, variant=variant, seed=seed, n_points=n_points, n_hits=n_hits, sample_rate=sample_rate,
                     n_samples=n_samples, noise=noise, damping=damping, n_max=n_max, dtype=dtype)
    faults = dict(double_hits=_pairs(double_hit, 2, "--double-hit"), clipped=_pairs(clip, 3, "--clip"),
                  dead_channel=dead_channel, missing_point=missing_point)
    cfg = build_config(config_file, overrides, parse_key_values(params, "--param"), _effects(effects), faults)
    check_size(estimate_bytes(cfg), f"--points {cfg.n_points} × --hits {cfg.n_hits} × --samples {cfg.n_samples}, "
                                    f"--n-max {cfg.n_max}")
    truth = truth or output.with_suffix(".truth.json")
    check_overwrite(output, overwrite)
    check_overwrite(truth, overwrite)
    bar = Progress("simulating")
    sim = simulate(cfg, progress=bar)
    bar.close()
    with atomic_path(truth, overwrite=overwrite) as tmp_truth:
        tmp_truth.write_text(dumps(sim.truth), encoding="utf-8")
        write_measurement(output, sim.measurement, overwrite=overwrite,
                          compression="gzip" if compress else None)
    if uff_dir is not None:
        uff_dir.mkdir(parents=True, exist_ok=True)
        _, mapping = write_uff_time(uff_dir, sim.measurement, overwrite=overwrite)
        write_text_atomic(uff_dir / "mapping.toml", mapping_toml(mapping), overwrite=overwrite)
    summary = {"output": str(output), "truth": str(truth), "n_points": sim.measurement.n_points,
               "n_hits": sim.measurement.n_hits, "n_channels": sim.measurement.n_channels,
               "n_samples": sim.measurement.n_samples, "sample_rate": sim.measurement.sample_rate,
               "n_modes_below_nyquist": len(sim.truth["modes"]), "faults": sim.truth["faults"]}
    if as_json:
        echo_json(summary)
    else:
        say(f"wrote {output} ({summary['n_points']} points × {summary['n_hits']} hits × "
                   f"{summary['n_channels']} channels) and {truth}")
