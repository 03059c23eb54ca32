"""docs/model.md section 12: the parameters, inputs and outputs as tables, generated from
parameters.py so that the document cannot drift from the package.

    python -m herringbone.model.document docs/model.md     rewrites the generated section
"""
from __future__ import annotations

from .parameters import INPUTS, OUTPUTS, PARAMETERS

GENERATED_BEGIN, GENERATED_END = "<!-- generated: parameters -->", "<!-- end generated -->"


def markdown_tables() -> str:
    """The parameters, inputs and outputs as markdown tables: name, unit, default (reference
    value; "derived" where computed from others), allowed values, component, meaning."""
    def allowed(p):
        if p.kind is bool:
            return "true or false"
        text = p.allowed.describe()
        return f"whole number {text}" if p.kind is int else text

    def default(p):
        if p.default is None:
            return "derived"
        return str(p.default).lower() if p.kind is bool else f"{p.default:g}"

    lines = ["| parameter | unit | default | allowed | component | meaning |",
             "|---|---|---|---|---|---|"]
    lines += [f"| `{p.name}` | {p.unit or '-'} | {default(p)} | {allowed(p)} | "
              f"{p.component or 'all'} | {p.description} |" for p in PARAMETERS.values()]
    lines += ["", "| input | unit | default | allowed | meaning |", "|---|---|---|---|---|"]
    lines += [f"| `{p.name}` | {p.unit} | {default(p)} | {allowed(p)} | {p.description} |"
              for p in INPUTS.values()]
    lines += ["", "| output | unit | type | meaning |", "|---|---|---|---|"]
    lines += [f"| `{o.name}` | {o.unit} | {'integer' if o.kind is int else 'real'} | "
              f"{o.description} |" for o in OUTPUTS.values()]
    return "\n".join(lines)


def with_generated_tables(text: str) -> str:
    """`text` (docs/model.md) with what stands between its generated-section markers replaced
    by `markdown_tables()`."""
    head, rest = text.split(GENERATED_BEGIN, 1)
    _, tail = rest.split(GENERATED_END, 1)
    return f"{head}{GENERATED_BEGIN}\n{markdown_tables()}\n{GENERATED_END}{tail}"


if __name__ == "__main__":  # python -m herringbone.model.document docs/model.md
    import sys
    from pathlib import Path

    document = Path(sys.argv[1])
    document.write_text(with_generated_tables(document.read_text(encoding="utf-8")),
                        encoding="utf-8")
