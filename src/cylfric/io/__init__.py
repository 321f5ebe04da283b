"""Readers and writers of test-bench files (data in SI, metadata as dicts)."""

from .writers import atomic_write_bytes, atomic_write_text, write_manifest, write_mts_text

__all__ = ["atomic_write_bytes", "atomic_write_text", "write_manifest", "write_mts_text"]
