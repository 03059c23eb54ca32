"""Close-match suggestions for a misspelt name (a scene, a parameter, an option, a command):
one home, so that every message says "did you mean" the same way."""
from __future__ import annotations

import difflib
from collections.abc import Iterable


def did_you_mean(word: str, choices: Iterable[str]) -> str:
    """"; did you mean 'NAME'?" for the closest of `choices` to `word` (difflib's ratio at least
    0.6), or "" when none is close; meant to end a one-line message."""
    found = difflib.get_close_matches(str(word), [str(choice) for choice in choices], n=1)
    return f"; did you mean {found[0]!r}?" if found else ""
