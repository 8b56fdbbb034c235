"""A case's bench: the bench file as written, with the case's variant applied — the campaign's
[params] sweep values, its [checks] in place of the bench's own, its max_time and the bus."""

from __future__ import annotations

import json
from typing import Any

from hil.bench import Bench
from hil.bench_file import _checks, parse_bench
from hil.bench_params import check_together
from hil.toml_fields import BenchFileError, FieldReader
from hil.campaign.spec import Case


def apply_variant(text: str, source: str, case: Case | Any, checks: dict[str, Any] | str | None,
                  max_time: float | None) -> Bench:
    """`case` is a Case or CaseInputs (both carry bus, params, events); raises BenchFileError."""
    bench = parse_bench(text, source)
    bench.bus = case.bus
    for name, value in case.params:
        bench.params[name] = value
    # A swept acc. and dec. time needs its speed in the bench or the sweep; an axis parameter, its axis (L26-1)
    together = check_together(bench.params, bench.axis_names)
    if together:
        raise BenchFileError(f"{source} with the campaign's [params]",
                             [f"params.{k!r}: {why}" if " " in k else f"params.{k}: {why}" for k, why in together])
    if max_time is not None:
        bench.max_time = max_time
    if isinstance(checks, str):
        checks = json.loads(checks) if checks else None
    if checks is not None:
        r = FieldReader()
        bench.checks = _checks(r, checks, tuple(bench.axis_names))
        if r.errors:
            raise BenchFileError(f"{source} with the campaign's [checks]", r.errors)
    if case.events:
        from hil.run_events import EventSpecError, parse_event, refuse_after_estop

        try:
            parsed = [(f"event {i}", parse_event(e, bench.axis_names)) for i, e in enumerate(case.events, 1)]
            refuse_after_estop(parsed, bench.cycle)  # recovery timed after the fault's E-stop (decision B58)
        except EventSpecError as exc:
            raise BenchFileError(f"{source}, fault {case.fault!r}" if hasattr(case, "fault") else source,
                                 [str(exc)]) from None
    return bench
