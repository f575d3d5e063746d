"""``groupfit fit --position COLUMN``: the check runs at positions, and the model's position terms."""

from __future__ import annotations

import argparse

import numpy as np

from groupfit.commands.common import configured_clock
from groupfit.commands.replay_positions import row_residuals
from groupfit.data import ERROR_LIMIT_UM, TEMP_RANGE_C
from groupfit.errors import InputError
from groupfit.model import DeadBand
from groupfit.position import choose_p0, cross_validate_order, load_position_run, residual_by_order, with_position
from groupfit.reference import refuse_as_temperature
from groupfit.settings import DataSettings


def check_position_options(args: argparse.Namespace) -> None:
    """The position and dead-band options that need another one."""
    if not args.position:
        for name in ("position_order", "position_ref"):
            if getattr(args, name) is not None:
                raise InputError(f"--{name.replace('_', '-')} needs --position COLUMN")
    if args.dead_band is not None and not args.position:
        raise InputError(
            "--dead-band needs --position COLUMN: the dead band holds a position model's compensation "
            "(docs/position.md)"
        )
    if args.position and getattr(args, "recalibrate", None) is not None:
        raise InputError(
            f"--recalibrate {args.recalibrate}: fit chooses no recalibration section for a position model; leave "
            "the option out"
        )
    if args.dead_band_ref is not None and args.dead_band is None:
        raise InputError("--dead-band-ref needs --dead-band C")
    if args.dead_band is not None and not (0 < args.dead_band <= 50):
        raise InputError(f"--dead-band {args.dead_band:g}: a threshold in (0, 50] degC")


def load_position_data(data: DataSettings, column: str):
    """The run of ``--position COLUMN`` (long or wide table; :func:`groupfit.position.load_position_run`)."""
    if not data.paths:
        raise InputError("no data given: pass --data CSV or set [data] path in the configuration")
    if len(data.paths) > 1:
        raise InputError("--position takes one run (a long or wide table of check runs)")
    limits = {
        "temp_range": TEMP_RANGE_C if data.temp_range is None else data.temp_range,
        "error_limit": ERROR_LIMIT_UM if data.error_limit is None else data.error_limit,
    }
    clock = configured_clock(data)
    columns = {"temps": list(data.temps) if data.temps is not None else None, "time": data.time, "error": data.error}
    return load_position_run(data.paths[0], column, **columns, **limits, **clock)


def position_model(args: argparse.Namespace, model, position_run) -> tuple:
    """The model with its position terms (and dead band), and the report's lines on them."""
    p0 = choose_p0(position_run, args.position_ref)
    order = args.position_order if args.position_order is not None else 1
    lines = []
    if order == "auto":
        chosen = cross_validate_order(position_run, p0=p0, intercept=model.intercept)
        order = chosen["order"]
        scores = ", ".join(f"{k}: {v:.3g}" for k, v in zip(chosen["orders"], chosen["rms_um"]))
        lines.append(f"position order {order} by cross-validation over held-out positions (RMS um: {scores})")
    dead_band = None
    if args.dead_band is not None:
        reference = args.dead_band_ref or (model.reference if model.reference not in (None, "start") else None)
        if reference is None:
            raise InputError("--dead-band needs its reference sensor: --dead-band-ref COLUMN (or --reference COLUMN)")
        if reference == position_run.column:
            raise InputError(f"--dead-band-ref '{reference}': the axis position, not a temperature; name the air's")
        if reference not in position_run.run.frame.columns:
            raise InputError(f"--dead-band-ref '{reference}': no such column in the run")
        refuse_as_temperature(position_run.run, reference, "--dead-band-ref", "name a temperature sensor (the air's)")
        dead_band = DeadBand(reference=reference, threshold_c=float(args.dead_band))
    fitted = with_position(model, position_run, order, p0, dead_band=dead_band)
    orders = residual_by_order(model, position_run, p0)
    fitted = fitted.replace(training={**(fitted.training or {}), "position_orders": orders})
    training = fitted.training
    lines.append(
        f"position {position_run.column}: order {order}, P0 = {p0:g} mm, travel {position_run.travel[0]:g} .. "
        f"{position_run.travel[1]:g} mm, {len(position_run.positions)} positions x {position_run.run.n_samples} "
        f"check runs; residual RMS {training['position_rms_um']:.3g} um, max {training['position_max_um']:.3g} um"
    )
    lines.append("residual by order (max / mean |e| um): " + order_table_text(orders))
    if dead_band is not None:
        fitted, line = with_dead_band_figures(fitted, position_run)
        lines.append(line)
    return fitted, "\n" + "\n".join(lines)


def with_dead_band_figures(model, position_run) -> tuple:
    """The model with the residual of its rule, dead band included, over the rows of its check runs
    (``training.dead_band_rms_um``, ``dead_band_max_um``: replay's figures on the same table), and the report's
    line saying the dead band is in the model and the figures above are without it."""
    residual = row_residuals(model, position_run)
    scored = residual[np.isfinite(residual)]
    rms, largest = float(np.sqrt(np.mean(scored**2))), float(np.max(np.abs(scored)))
    band = model.dead_band
    model = model.replace(training={**(model.training or {}), "dead_band_rms_um": rms, "dead_band_max_um": largest})
    line = (
        f"dead band {band.threshold_c:g} degC against {band.reference}: in the model (the compensation is held while "
        f"every input is within it); with it the residual is RMS {rms:.3g} um, max {largest:.3g} um over the rows, "
        "as replay gives on this table (training.dead_band_rms_um); the figures above are of the model without it"
    )
    return model, line


def order_table_text(orders: list[dict]) -> str:
    """The per-order residual table in one line: ``1: 0.53 / 0.19, 2: …``."""
    return ", ".join(f"{row['order']}: {row['max_um']:.3g} / {row['mean_um']:.3g}" for row in orders)


__all__ = ["check_position_options", "load_position_data", "position_model"]
