"""The modal stage's options (``lsce``, ``run``): band, model orders, the spatial split, the
pole estimator, the selection's thresholds."""

from __future__ import annotations

from dataclasses import dataclass

from tiremodal_cli.errors import ParameterError
from tiremodal_cli.modal.stabilization import StabilizationOptions

__all__ = ["ModalOptions"]


@dataclass(frozen=True)
class ModalOptions:
    """Options of the modal stage.

    band_hz : analysis band (default: the FRFs' lines above 0 Hz)
    max_order : highest model order of the sweep (orders 2 … max_order)
    spatial : "auto" (split into circumferential orders when the points go round a tread),
              "on" or "off"
    method : pole estimator: "lsce", "plscf" (poly-reference LSCF, :mod:`.plscf`), or
              "both" (:func:`modal_table_from_frf` runs the two and marks the modes they
              agree on as confirmed)
    min_significance : reject a mode explaining less than this share of the response at
              its own frequency (a pole fitted to noise)
    poly : with the spatial split, sweep an order group that holds a cos and a sin
              component as two references (poly-reference LSCE, or pLSCF with
              ``method="plscf"``), so that split pairs resolve; orders 1 … ``poly_order``
    skip : LSCE's first impulse-response sample in the autoregression (single reference)
    workers : threads that solve a poly-reference sweep's model orders (LAPACK releases the
              GIL; the poles are the same to the bit whatever the number)
    order_within_band : lower the highest order to what the band's lines allow (``run``)
    refine : refine the adopted poles near the band's edges by variable-projection least
              squares in their order group's FRFs, kept where the physical FRFs agree
              (:mod:`.refine`; docs/lsce.md, "Pole refinement": near the edges LSCE biases
              modes by up to 0.9 %; in the band's middle, where an added mass mixes the
              orders, the group's rows are no complete model and refining there moved
              right modes off), and the weak poles (kept by the own-peak rule) with
              their group's dropped poles held in the basis (session 12); where the groups are a
              complete model, the strong poles alone in their window too (session 42)
    guard : re-estimate the poles the band's wrap biases (within 6 half-widths of another
              pole's image across the wrap) in a second sweep with a guard band after the
              band's top, each kept where the group's rows fit better (:mod:`.guard`); every
              other pole stays the first sweep's. Docs/lsce.md, "Guard band across the wrap"
    beside : add a pole where a poly-reference group's residual holds a mode beside its
              kept poles, judged by nested fits (:mod:`.beside`)
    """

    band_hz: tuple[float, float] | None = None
    max_order: int = 120
    spatial: str = "auto"
    min_significance: float = 0.05
    stabilization: StabilizationOptions = StabilizationOptions()
    rtol_svd: float = 1e-4
    method: str = "lsce"
    poly: bool = True
    poly_order: int = 30
    skip: int = 0
    workers: int = 1
    order_within_band: bool = False
    refine: bool = True
    guard: bool = True
    beside: bool = True

    def check(self):
        if self.spatial not in ("auto", "on", "off"):
            raise ParameterError(f"spatial={self.spatial!r}; allowed: auto, on, off")
        if self.method not in ("lsce", "plscf", "both"):
            raise ParameterError(f"method={self.method!r}; allowed: lsce, plscf, both")
        if not 2 <= self.max_order <= 400:
            raise ParameterError(f"max_order={self.max_order} must be 2 … 400")
        if self.poly_order < 1 or self.skip < 0:
            raise ParameterError(f"poly_order={self.poly_order} must be ≥ 1 and skip={self.skip} ≥ 0")
        if not 1 <= self.workers <= 64:
            raise ParameterError(f"workers={self.workers} must be 1 … 64")
