"""find_duplicates reads the ends of same-size files first (issue 27): the copies it finds are
still exactly the files with an earlier file's bytes."""

from __future__ import annotations

import pytest

from cylfric.io.campaign import EDGE_BYTES, find_duplicates


@pytest.mark.parametrize("size", [10, EDGE_BYTES + 10, 3 * EDGE_BYTES])
def test_same_ends_different_middle_is_no_copy_and_equal_bytes_are(tmp_path, size):
    body = bytearray(b"x" * size)
    files = {}
    for name, change in (("a.txt", None), ("b.txt", size // 2), ("c.txt", None)):
        data = bytearray(body)
        if change is not None:
            data[change] = ord("y")  # the middle (or, for short files, anywhere)
        files[name] = tmp_path / name
        files[name].write_bytes(bytes(data))
    found = find_duplicates([files["a.txt"], files["b.txt"], files["c.txt"]])
    assert found == {files["c.txt"]: files["a.txt"]}


def test_different_ends_are_not_hashed_whole(tmp_path, monkeypatch):
    import cylfric.io.campaign as campaign

    hashed = []
    monkeypatch.setattr(campaign, "file_sha256", lambda p: hashed.append(p) or "same")
    for i in range(3):
        (tmp_path / f"{i}.txt").write_bytes(bytes([i]) * (3 * EDGE_BYTES))
    assert find_duplicates(sorted(tmp_path.iterdir())) == {}
    assert hashed == []


def test_edges_that_agree_by_chance_are_still_told_apart_by_sha256(tmp_path, monkeypatch):
    """The edge check is only a filter (a CRC-32): files it cannot tell apart, as if every
    checksum collided, are compared whole, and only true copies are reported."""
    import cylfric.io.campaign as campaign

    monkeypatch.setattr(campaign, "_edges_digest", lambda path, size: 0)
    files = []
    for name, fill in (("a.txt", b"a"), ("b.txt", b"b"), ("c.txt", b"a"), ("d.txt", b"b")):
        files.append(tmp_path / name)
        files[-1].write_bytes(fill * (3 * EDGE_BYTES))
    a, b, c, d = files
    assert find_duplicates(files) == {c: a, d: b}
