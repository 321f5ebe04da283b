"""What an export wrote and, for a lossy target, what it loses (:class:`ExportResult`)."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

__all__ = ["ExportResult"]


@dataclass(frozen=True)
class ExportResult:
    """The files an export wrote and its loss reports.

    Attributes
    ----------
    target : str
        The export target (``"simscape"``, ``"fmu"``, ...).
    files : tuple of Path
        Every file written, in a fixed order.
    loss : tuple of LossReport or None
        The loss reports of a lossy target (one per target block), None for a lossless
        target (FMU, MATLAB, Modelica: the full model).
    """

    target: str
    files: tuple
    loss: tuple | None = None

    @property
    def lossless(self) -> bool:
        """True when the target carries the full model (no loss report)."""
        return self.loss is None

    def summary(self) -> str:
        """Text lines: the files and, for a lossy target, each block's RMS and maximum."""
        folder = Path(self.files[0]).parent if self.files else Path(".")
        lines = [f"{self.target}: {len(self.files)} file(s) in {folder}"]
        if self.loss is None:
            lines.append("  lossless: the full pressure-dependent LuGre model")
        else:
            lines += [f"  {report.summary()}" for report in self.loss]
        return "\n".join(lines)
