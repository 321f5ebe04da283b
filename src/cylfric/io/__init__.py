"""Readers and writers of test-bench files (data in SI, metadata as dicts).

``read_*(path, ...) -> (data, metadata)``; campaign discovery and configuration in
:mod:`cylfric.io.campaign`.
"""

from .campaign import (
    Campaign,
    CampaignConfig,
    OilSettings,
    RunInfo,
    discover_runs,
    load_config,
    name_tokens,
    read_run,
)
from .matfile import read_mat
from .text import BenchFileError, read_bench_text, read_delimited, read_mts_text
from .writers import atomic_write_bytes, atomic_write_text, write_manifest, write_mts_text

__all__ = [
    "BenchFileError",
    "Campaign",
    "CampaignConfig",
    "OilSettings",
    "RunInfo",
    "discover_runs",
    "load_config",
    "name_tokens",
    "read_run",
    "read_bench_text",
    "read_mts_text",
    "read_delimited",
    "read_mat",
    "atomic_write_bytes",
    "atomic_write_text",
    "write_manifest",
    "write_mts_text",
]
