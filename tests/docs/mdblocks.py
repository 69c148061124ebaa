"""The fenced blocks of a markdown file, with the directives written above them.

A directive is an HTML comment on the lines right above a block's fence (a
reader of the rendered page does not see it):

    <!-- doc-test: small --steps 60 --reps 1 -->
    ```sh
    build/bin/afford experiment base --reps 3 --out out/base
    ```

tests/docs/run_blocks.py says what each directive does.
"""
import re
from dataclasses import dataclass, field
from pathlib import Path

FENCE = re.compile(r"^```([\w+-]*)\s*$")
DIRECTIVE = re.compile(r"^<!--\s*doc-test:\s*(\S+)\s*(.*?)\s*-->\s*$")


@dataclass
class Block:
    lang: str
    start: int  # the line number of the block's first line (after the fence)
    text: str
    section: str  # the `##` heading it is under
    directives: list = field(default_factory=list)  # (name, argument) of each directive above the fence


def blocks(path: Path):
    section, lang, start, body, above = "", None, 0, [], []
    for n, line in enumerate(path.read_text().splitlines(), 1):
        if lang is None:
            m, d = FENCE.match(line), DIRECTIVE.match(line)
            if line.startswith("## "):
                section = line[3:]
            if m:
                lang, start, body, directives = m.group(1), n + 1, [], above
            elif d:
                above = above + [(d.group(1), d.group(2))]
                continue
            above = []
        elif line.startswith("```"):
            yield Block(lang, start, "\n".join(body), section, directives)
            lang = None
        else:
            body.append(line)
