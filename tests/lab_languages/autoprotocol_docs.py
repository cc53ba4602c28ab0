"""Finds the complete Autoprotocol documents among the examples in autoprotocol-python's own
documentation (the docstrings of the installed package: JSON objects with `refs` and
`instructions`) and writes each as a file: `python autoprotocol_docs.py OUT_DIR`. These are the
public protocols the import tests import as found (tests/import_autoprotocol.rs); nothing of them
is committed here.
"""
import inspect
import json
import sys
from pathlib import Path

import autoprotocol
import autoprotocol.harness
import autoprotocol.protocol

out = Path(sys.argv[1])
out.mkdir(parents=True, exist_ok=True)


def objects(text):
    """Every balanced {...} in text that parses as a JSON object."""
    found = []
    for start, c in enumerate(text):
        if c != "{":
            continue
        depth = 0
        for end in range(start, len(text)):
            if text[end] == "{":
                depth += 1
            elif text[end] == "}":
                depth -= 1
                if depth == 0:
                    try:
                        found.append(json.loads(text[start : end + 1]))
                    except ValueError:
                        pass
                    break
    return found


texts = []
for module in (autoprotocol.protocol, autoprotocol.harness):
    source = inspect.getsource(module)
    texts.append((module.__name__, source))
seen = set()
n = 0
for name, text in texts:
    for doc in objects(text):
        if not (isinstance(doc, dict) and "refs" in doc and "instructions" in doc):
            continue
        key = json.dumps(doc, sort_keys=True)
        if key in seen:
            continue
        seen.add(key)
        n += 1
        (out / f"{name.split('.')[-1]}_{n:02}.json").write_text(json.dumps(doc, indent=2) + "\n")
print(n)
