"""User text as data: one escaping function per target language.

Datasheets, campaign folders, manifest rows and catalogue entries come from other people, and
their text fields (name, notes, method, reasons, folder and file names) end up in files that
other tools read as code: C sources compiled into an FMU, MATLAB and Simscape scripts, Modelica
packages, Hopsan HCOM scripts, XML model descriptions, Markdown and HTML pages, and the
terminal. Every place that puts such text into generated code goes through one of the
functions below, which keep the text inside a literal or a comment of that language, on one
line (see docs/security.md for the threat model).

The common step is :func:`printable`: control characters, line and paragraph separators,
format characters (bidirectional overrides included) and lone surrogates become visible
escapes (``\\x0a``, ``\\u202e``), so the text is one line of printable characters.
Identifiers derived from names are mangled by :func:`identifier` to
``[A-Za-z_][A-Za-z0-9_]*``; the original is kept as a string by the caller.

Examples
--------
>>> c_comment("evil */ system(1); /*")
'evil * / system(1); / *'
>>> matlab_string("it's\\nnew")
"'it''s\\\\x0anew'"
>>> identifier("3 bar seal / PK", default="cylfric")
'cylfric_3_bar_seal___PK'
"""

from __future__ import annotations

import html
import unicodedata
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    import pandas as pd

__all__ = [
    "printable",
    "c_comment",
    "c_string",
    "matlab_comment",
    "matlab_string",
    "modelica_string",
    "hcom_comment",
    "markdown_text",
    "html_text",
    "xml_attr",
    "plot_text",
    "terminal",
    "identifier",
    "csv_text",
    "csv_frame",
    "COMMENT_LIMIT",
]

COMMENT_LIMIT = 240
"""Longest user text [characters] a generated comment carries; longer text ends in ``[...]``."""

_ESCAPED_CATEGORIES = ("Cc", "Cf", "Cs", "Co", "Cn", "Zl", "Zp")


def _escape_char(c: str) -> str:
    code = ord(c)
    if code < 0x100:
        return f"\\x{code:02x}"
    if code < 0x10000:
        return f"\\u{code:04x}"
    return f"\\U{code:08x}"


def printable(text: object, *, limit: int | None = None, ascii_only: bool = False) -> str:
    """``text`` as one line of printable characters.

    Parameters
    ----------
    text : object
        Any value; ``str(text)`` is escaped.
    limit : int, optional
        Longest result [characters]; longer text is cut and ends in ``" [...]"``.
    ascii_only : bool
        Escape every non-ASCII character too (for C sources).

    Returns
    -------
    str
        The text with control, format and separator characters (category Cc, Cf, Cs, Co,
        Cn, Zl, Zp: newlines, NUL, ESC, bidirectional overrides, lone surrogates) written as
        ``\\xNN``, ``\\uNNNN`` or ``\\UNNNNNNNN``; a space is kept, a tab becomes ``\\x09``.
    """
    out = []
    for c in str(text):
        if (ascii_only and ord(c) > 0x7E) or unicodedata.category(c) in _ESCAPED_CATEGORIES:
            out.append(_escape_char(c))
        else:
            out.append(c)
    result = "".join(out)
    if limit is not None and len(result) > limit:
        result = result[: max(limit - 6, 0)] + " [...]"
    return result


def _break(text: str, *pairs: tuple[str, str]) -> str:
    """Replace each opener/closer until none is left (a replacement cannot form a new one)."""
    changed = True
    while changed:
        changed = False
        for old, new in pairs:
            if old in text:
                text = text.replace(old, new)
                changed = True
    return text


def c_comment(text: object, *, limit: int | None = COMMENT_LIMIT) -> str:
    """Text to place between ``/* `` and `` */`` in C: ASCII, one line, no ``*/`` or ``/*``."""
    return _break(printable(text, limit=limit, ascii_only=True), ("*/", "* /"), ("/*", "/ *"))


def c_string(text: object) -> str:
    """A C string literal (with its quotes) holding ``text``'s UTF-8 bytes.

    Printable ASCII stays as it is except ``\\``, ``"`` and ``?`` (trigraphs), which are
    escaped; every other byte is written as a three-digit octal escape.
    """
    out = ['"']
    for byte in str(text).encode("utf-8", "surrogatepass"):
        c = chr(byte)
        if c in '\\"?':
            out.append("\\" + c)
        elif 0x20 <= byte <= 0x7E:
            out.append(c)
        else:
            out.append(f"\\{byte:03o}")
    out.append('"')
    return "".join(out)


def matlab_comment(text: object, *, limit: int | None = COMMENT_LIMIT) -> str:
    """Text to place after ``%`` on one MATLAB/Octave line (no line break can end it)."""
    return printable(text, limit=limit)


def matlab_string(text: object) -> str:
    """A MATLAB/Octave character-vector literal ``'...'`` (quotes doubled, one line)."""
    return "'" + printable(text).replace("'", "''") + "'"


def modelica_string(text: object, *, quotes: bool = True) -> str:
    """A Modelica string literal ``"..."`` (backslash and quote escaped, one line).

    ``quotes=False`` gives the inside only, to place within a literal of the template.
    """
    inner = printable(text).replace("\\", "\\\\").replace('"', '\\"')
    return f'"{inner}"' if quotes else inner


def hcom_comment(text: object, *, limit: int | None = COMMENT_LIMIT) -> str:
    """Text to place after ``#`` on one line of a Hopsan HCOM script."""
    return printable(text, limit=limit)


def html_text(text: object) -> str:
    """HTML text or attribute value (``& < > " '`` as entities, one line)."""
    return html.escape(printable(text), quote=True)


_MARKDOWN_SPECIAL = "\\`*_{}[]()#+-.!|~"  # < > & become entities below


def markdown_text(text: object, *, limit: int | None = COMMENT_LIMIT) -> str:
    """Text for Markdown: one line, every Markdown punctuation escaped with a backslash."""
    line = printable(text, limit=limit)
    line = "".join("\\" + c if c in _MARKDOWN_SPECIAL else c for c in line)
    return html.escape(line, quote=False)


def plot_text(text: object, *, limit: int | None = 80) -> str:
    """Text for a matplotlib label or title: one line, ``$`` escaped (no mathtext parsing)."""
    return printable(text, limit=limit).replace("$", r"\$")


def xml_attr(text: object) -> str:
    """An XML attribute value with its quotes (only characters XML 1.0 allows, one line)."""
    # imported here: xml.sax.saxutils brings urllib.request, http.client and email (about
    # 60 ms) into every command's start-up otherwise
    from xml.sax.saxutils import quoteattr

    return quoteattr(printable(text))


def terminal(text: object, *, markup: bool = True, multiline: bool = False) -> str:
    """Text for a rich console: control codes (ANSI ESC) and, by default, markup escaped.

    Parameters
    ----------
    text : object
        User text (a name, a file name, a reason), or a message holding some.
    markup : bool
        Escape rich markup (``[bold]``, ``[/]``): for text printed with markup on, or put in
        a table cell. ``False`` for text printed with ``markup=False``.
    multiline : bool
        Keep line breaks (``\\n``) of a message of several lines; every other control
        character is still escaped.
    """
    if multiline:
        lines = str(text).split("\n")
        return "\n".join(terminal(line, markup=markup) for line in lines)
    line = printable(text)
    if not markup:
        return line
    from rich.markup import escape

    return escape(line)


def identifier(name: object, *, default: str = "cylfric", max_length: int = 48) -> str:
    """An identifier ``[A-Za-z_][A-Za-z0-9_]*`` made of ``name`` (C, MATLAB, Modelica).

    Every character that is not an ASCII letter or digit becomes ``_`` and leading and
    trailing ``_`` are stripped; a name that does not start with a letter gets
    ``default + "_"`` in front (``default`` alone when nothing is left); at most
    ``max_length`` characters.
    """
    text = "".join(c if (c.isascii() and c.isalnum()) else "_" for c in str(name)).strip("_")
    if not text or not text[0].isalpha():
        text = f"{default}_{text}" if text else default
    return text[:max_length]


CSV_FORMULA_START = ("=", "+", "-", "@")
"""First characters that make a spreadsheet read a CSV cell as a formula (OWASP, "CSV
injection"): such a cell is written with a leading ``'``."""


def csv_text(text: object) -> object:
    """A text cell of a CSV file cylfric writes: one line of printable characters
    (:func:`printable`), and a leading ``'`` before ``= + - @`` so that a spreadsheet shows
    ``=HYPERLINK(...)`` as text rather than running it. Anything but ``str`` (numbers,
    None, NaN) is returned as it is.

    >>> csv_text('=HYPERLINK(1)')
    "'=HYPERLINK(1)"
    >>> print(csv_text('run' + chr(27) + '[31m.txt'))
    run\\x1b[31m.txt
    """
    if not isinstance(text, str):
        return text
    if not text.isprintable():  # C-fast test first: most names need nothing
        text = printable(text)
    return "'" + text if text.startswith(CSV_FORMULA_START) else text


def csv_frame(frame: pd.DataFrame) -> pd.DataFrame:
    """A copy of the DataFrame ``frame`` whose text cells went through :func:`csv_text`
    (each distinct text once: a points table repeats its few file names thousands of
    times); numeric columns untouched; ``frame`` itself when nothing changes."""
    changed = {}
    for name in frame.columns:
        column = frame[name]
        if column.dtype != object and str(column.dtype) not in ("string", "str"):
            continue
        texts = [v for v in column.unique() if isinstance(v, str)]
        mapping = {v: csv_text(v) for v in texts}
        if any(k != v for k, v in mapping.items()):
            changed[name] = column.map(
                lambda v, m=mapping: m.get(v, v) if isinstance(v, str) else v
            )
    if not changed:
        return frame
    out = frame.copy()
    for name, column in changed.items():
        out[name] = column
    return out
