#!/usr/bin/env python3
"""Per-file compile commands for clang-tidy from a unity build's compile_commands.json.

A unity build (the release preset) lists its generated unity_N_cxx.cxx files, not the sources
they include, so clang-tidy finds no command for a source. This writes DIR/compile_commands.json
with one entry per source: its own entry when it has one (files kept out of the unity batches),
else its unity file's command with the source in place of the unity file. Prints the sources
found; sources the build does not compile are left out.
usage: per_file_commands.py BUILD_DIR OUT_DIR SOURCE...
"""
import json
import os
import re
import sys


def main():
    build, out_dir, sources = sys.argv[1], sys.argv[2], sys.argv[3:]
    with open(os.path.join(build, "compile_commands.json")) as f:
        entries = json.load(f)
    by_file = {}
    include = re.compile(r'^#include "(.+)"$')
    for e in entries:
        by_file.setdefault(os.path.realpath(e["file"]), e)
        if "/Unity/unity_" not in e["file"]:
            continue
        with open(e["file"]) as unity:
            for line in unity:
                m = include.match(line.strip())
                if m:
                    path = os.path.realpath(m.group(1))
                    by_file.setdefault(path, {
                        "directory": e["directory"],
                        "command": e["command"].replace(e["file"], path),
                        "file": path,
                    })
    chosen = []
    for s in sources:
        e = by_file.get(os.path.realpath(s))
        if e is not None:
            chosen.append(e)
            print(s)
    os.makedirs(out_dir, exist_ok=True)
    with open(os.path.join(out_dir, "compile_commands.json"), "w") as f:
        json.dump(chosen, f, indent=1)


if __name__ == "__main__":
    main()
