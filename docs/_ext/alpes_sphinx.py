"""Local Sphinx extension of the alpes_dyn docs: content generated at build time from the package.

Docstrings
----------
The package's docstrings use numpy-style sections, sometimes with the compact ``name: text``
lines and a closing paragraph after the fields. :func:`normalize_docstring` runs before napoleon
and rewrites them into the layout napoleon expects (``name`` then the indented text; two blank
lines to close a field section), so they render as parameter descriptions, not as types.

Directives
----------
``.. alpes-parameters::``
    A table of the shipped parameter file ``alpes_dyn/data/alpes_hand.toml`` (value, unit,
    source, description and, for an assumed value, its reason). Option ``:source: report`` or
    ``:source: assumed`` keeps one kind only; ``:sections: finger, thumb`` keeps some sections.
``.. alpes-command:: report --points 5``
    Runs ``alpes-dyn`` with these arguments in-process and shows the command and what it prints.
    Option ``:strip-timing:`` drops lines that only report a wall time (they change run to run).
"""

from __future__ import annotations

import contextlib
import io
import re
import shlex
from typing import Any

import numpy as np
from docutils import nodes
from docutils.parsers.rst import directives
from docutils.statemachine import StringList
from sphinx.application import Sphinx
from sphinx.util.docutils import SphinxDirective


def _fmt_value(value: Any) -> str:
    if isinstance(value, tuple):
        return ", ".join(value)
    if isinstance(value, np.ndarray):
        return ", ".join(f"{x:.6g}" for x in value)
    if isinstance(value, float):
        return f"{value:.6g}"
    return str(value)


def _cell(text: str) -> str:
    """One list-table cell: inline literal-safe, one line."""
    text = " ".join(str(text).split())
    return text.replace("*", r"\*").replace("|", r"\|") if text else " "


class ParametersDirective(SphinxDirective):
    """Table of the parameter file, generated from :func:`alpes_dyn.load_params`."""

    has_content = False
    option_spec = {"source": directives.unchanged, "sections": directives.unchanged}

    def run(self) -> list[nodes.Node]:
        from alpes_dyn.model.params import default_params_path, load_params

        p = load_params()
        self.env.note_dependency(str(default_params_path()))
        source = self.options.get("source", "").strip()
        sections = [s.strip() for s in self.options.get("sections", "").split(",") if s.strip()]
        rows = []
        for key, prm in p.raw.items():
            if source and prm.source != source:
                continue
            if sections and key.split(".")[0] not in sections:
                continue
            note = _cell(prm.description) if prm.description else ""
            if prm.source == "assumed":
                note = (note.rstrip(".") + ". " if note.strip() else "") + "*Assumed:* " + _cell(prm.reason)
            rows.append((f"``{key}``", _cell(_fmt_value(prm.value)), _cell(prm.unit), prm.source, note or " "))
        lines = [".. list-table::", "   :header-rows: 1", "   :widths: 18 22 10 9 41", "",
                 "   * - field", "     - value", "     - unit", "     - source", "     - description"]
        for r in rows:
            lines.append(f"   * - {r[0]}")
            lines += [f"     - {c}" for c in r[1:]]
        container = nodes.container()
        self.state.nested_parse(StringList(lines, source="alpes_hand.toml"), self.content_offset, container)
        return container.children


class CommandDirective(SphinxDirective):
    """Run ``alpes-dyn ARGS`` in-process and show its output."""

    required_arguments = 1
    final_argument_whitespace = True
    option_spec = {"strip-timing": directives.flag}

    def run(self) -> list[nodes.Node]:
        from alpes_dyn.cli import main

        argv = shlex.split(self.arguments[0])
        out, err = io.StringIO(), io.StringIO()
        with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
            try:
                code = main(argv)
            except SystemExit as exc:  # --help exits through argparse
                code = exc.code if isinstance(exc.code, int) else 0
        if code != 0:
            raise self.error(f"alpes-dyn {self.arguments[0]} exited {code}: {err.getvalue().strip()}")
        text = out.getvalue().rstrip()
        if "strip-timing" in self.options:
            text = "\n".join(ln for ln in text.splitlines() if not re.fullmatch(r"\s*[0-9.]+ s\s*", ln)).rstrip()
        block = nodes.literal_block(text=f"$ alpes-dyn {self.arguments[0]}\n{text}")
        block["language"] = "console"
        return [block]


_FIELD_SECTIONS = {"parameters", "other parameters", "attributes", "returns", "yields", "raises", "warns"}
_COMPACT = re.compile(r"^([A-Za-z_*][\w*]*(?:\s*,\s*[A-Za-z_*][\w*]*)*):\s+(\S.*)$")
_NAME_ONLY = re.compile(r"^[A-Za-z_*][\w*.]*(?:\s*,\s*[A-Za-z_*][\w*]*)*\s*(?::.*)?$")


_PIPES = re.compile(r"(``.*?``)|\|")


def _escape_pipes(lines: list[str]) -> list[str]:
    """Escape ``|`` outside inline literals, literal blocks and doctests: ``|q_hat - q|`` is an
    absolute value in these docstrings, not a reStructuredText substitution reference."""
    out, literal_indent = [], None
    prev = ""
    for line in lines:
        indent = len(line) - len(line.lstrip())
        if literal_indent is not None and line.strip() and indent <= literal_indent:
            literal_indent = None
        if literal_indent is None and prev.rstrip().endswith("::") and line.strip():
            literal_indent = len(prev) - len(prev.lstrip())
        stripped = line.lstrip()
        if literal_indent is None and "|" in line and not stripped.startswith((">>>", "...")):
            line = _PIPES.sub(lambda m: m.group(1) or r"\|", line)
        out.append(line)
        if line.strip():
            prev = line
    return out


def normalize_docstring(app: Sphinx, what: str, name: str, obj: Any, options: Any, lines: list[str]) -> None:
    """Rewrite compact numpy fields (``name: text``) and close field sections before free text;
    escape absolute-value bars."""
    lines[:] = _escape_pipes(lines)
    out: list[str] = []
    section: str | None = None
    i = 0
    while i < len(lines):
        line = lines[i]
        nxt = lines[i + 1] if i + 1 < len(lines) else ""
        if line.strip() and set(nxt.strip()) == {"-"} and len(nxt.strip()) >= 3:
            section = line.strip().lower()
            out += [line, nxt]
            i += 2
            continue
        base = line[: len(line) - len(line.lstrip())]
        if section in _FIELD_SECTIONS and line.strip() and base == "":
            if out and out[-1] == "" and not _NAME_ONLY.match(line.strip()):
                out.append("")  # free text after the fields: two blank lines end the section
                section = None
            else:
                m = _COMPACT.match(line.strip())
                if m and " : " not in line:
                    names = m.group(1)
                    if section == "attributes":  # a field argument with spaces would read as "type name"
                        names = ",".join(n.strip() for n in names.split(","))
                    out += [names, "    " + m.group(2)]
                    i += 1
                    continue
        out.append(line)
        i += 1
    lines[:] = out


def setup(app: Sphinx) -> dict[str, Any]:
    app.connect("autodoc-process-docstring", normalize_docstring, priority=400)
    app.add_directive("alpes-parameters", ParametersDirective)
    app.add_directive("alpes-command", CommandDirective)
    return {"version": "1", "parallel_read_safe": True, "parallel_write_safe": True}
