"""Campaigns: a matrix of lock-step runs (programs × benches × buses × overrides × parameter
sweeps × fault injections) run serially or on Dask, gathered into one Parquet table.

    from hil.campaign import run_campaign, Engine
    outcome = run_campaign("nightly.toml", "out/nightly", Engine(workers=2))

See docs/guide/campaigns.md.
"""

from hil.campaign.engine import Engine
from hil.campaign.orchestrate import CampaignOutcome, run_campaign

__all__ = ["CampaignOutcome", "Engine", "run_campaign"]
