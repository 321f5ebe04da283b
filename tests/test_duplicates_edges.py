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
