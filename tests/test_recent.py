"""symkin.core.recent.Recent: the first value kept under a key wins, a read makes a key the most
recent, and beyond its size the least recent goes."""

from __future__ import annotations

from symkin.core.recent import Recent


def test_first_kept_wins_and_the_least_recent_goes():
    memo = Recent(2)
    first = ["a"]
    assert memo.keep("a", first) is first
    assert memo.keep("a", ["other"]) is first  # a second derivation of the same key: the first
    memo.keep("b", 2)
    assert memo.get("a") is first  # "a" is now the most recent
    memo.keep("c", 3)
    assert memo.get("b") is None and memo.get("a") is first and memo.get("c") == 3
    assert memo.get("missing") is None


def test_get_or_make_makes_once_per_key():
    memo: Recent[str, list] = Recent(4)
    made = []

    def make(value):
        made.append(value)
        return [value]

    first = memo.get_or_make("a", lambda: make(1))
    assert memo.get_or_make("a", lambda: make(2)) is first  # kept: not made again
    assert memo.get_or_make("b", lambda: make(3)) == [3]
    assert made == [1, 3]
