"""Close-match suggestions for a misspelt name (a scene, a parameter, an option, a command):
one home, so that every message says "did you mean" the same way."""
from __future__ import annotations

import difflib
from collections.abc import Iterable


def did_you_mean(word: str, choices: Iterable[str]) -> str:
    """"; did you mean 'NAME'?" for the one of `choices` that is `word` in other case
    ("c_shaft_in" for "C_shaft_in", which difflib ranks below "h_shaft_in"), else the one
    that `word` begins (a name cut short, "zeta" for "zeta_mesh", which difflib ranks below
    "beta"), else the closest to `word` (difflib's ratio at least 0.6), or "" when none is
    close; meant to end a one-line message."""
    word, names = str(word), [str(choice) for choice in choices]
    cased = [name for name in names if name.lower() == word.lower()]
    begun = [name for name in names if len(word) >= 3 and name.startswith(word)]
    found = (cased if len(cased) == 1 else begun if len(begun) == 1
             else difflib.get_close_matches(word, names, n=1))
    return f"; did you mean {found[0]!r}?" if found else ""
