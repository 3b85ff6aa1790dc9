#!/usr/bin/env python3
"""Static checks of docker/Dockerfile that need no Docker engine (none runs on our build machines).

Checks what a build would trip over first and what this repository promises about the image:
  * the base image is debian:bookworm (ARG DEBIAN_IMAGE) and stage names are unique;
  * COPY sources exist in the repository and are not excluded by Dockerfile.dockerignore;
    COPY --from names an earlier stage;
  * every RUN is exec form and runs a script of this repository that is executable, passes
    `bash -n`, and was copied into the image (or the whole context was, in the build stage);
  * packages come only through scripts/install-deps.sh (no apt-get, pip, curl or wget);
  * the final stage is `runtime`, runs as a non-root user and has a HEALTHCHECK in exec form.
Usage: check-dockerfile.py [DOCKERFILE]   (exit 0: ok; 1: problems, each printed)
"""
import fnmatch
import json
import os
import re
import subprocess
import sys

here = os.path.dirname(os.path.abspath(__file__))
repo = os.path.dirname(here)
path = sys.argv[1] if len(sys.argv) > 1 else os.path.join(here, "Dockerfile")
problems = []


def problem(line, msg):
    problems.append(f"{os.path.relpath(path, repo)}:{line}: {msg}")


# Join continuation lines, drop comments and blank lines.
instructions = []
with open(path, encoding="utf-8") as f:
    buf, start = "", 0
    for no, raw in enumerate(f, 1):
        line = raw.rstrip("\n")
        if not buf and (not line.strip() or line.lstrip().startswith("#")):
            continue
        if not buf:
            start = no
        if line.endswith("\\"):
            buf += line[:-1] + " "
            continue
        buf += line
        instructions.append((start, buf.strip()))
        buf = ""

ignore = []
ignore_file = path + ".dockerignore"
if os.path.exists(ignore_file):
    with open(ignore_file, encoding="utf-8") as f:
        ignore = [l.strip() for l in f if l.strip() and not l.startswith("#")]


def ignored(rel):
    parts = rel.split("/")
    for pat in ignore:
        p = pat.lstrip("/")
        for i in range(1, len(parts) + 1):
            prefix = "/".join(parts[:i])
            if fnmatch.fnmatch(prefix, p) or (p.startswith("**/") and fnmatch.fnmatch(parts[i - 1], p[3:])):
                return True
    return False


args = {}
stages = []  # dicts: name, copied (image path -> repo path), whole_context_at
for no, ins in instructions:
    kw, _, rest = ins.partition(" ")
    kw = kw.upper()
    if kw == "ARG":
        name, _, default = rest.partition("=")
        args[name.strip()] = default.strip()
        continue
    if kw == "FROM":
        m = re.match(r"(\S+)(?:\s+AS\s+(\S+))?$", rest, re.I)
        if not m:
            problem(no, f"cannot read FROM '{rest}'")
            continue
        image, name = m.group(1), m.group(2)
        if image.startswith("${"):
            image = args.get(image[2:-1], image)
        if image not in [s["name"] for s in stages] and image != "debian:bookworm":
            problem(no, f"base image '{image}' is neither debian:bookworm nor an earlier stage")
        if name in [s["name"] for s in stages]:
            problem(no, f"stage name '{name}' used twice")
        parent = next((s for s in stages if s["name"] == image), None)
        stages.append({
            "name": name, "line": no, "workdir": "/",
            "copied": dict(parent["copied"]) if parent else {},
            "context_at": parent["context_at"] if parent else None,
            "user": parent["user"] if parent else None,
            "healthcheck": None,
        })
        continue
    if not stages:
        problem(no, f"{kw} before the first FROM")
        continue
    st = stages[-1]
    if kw == "WORKDIR":
        st["workdir"] = rest if rest.startswith("/") else os.path.join(st["workdir"], rest)
    elif kw == "USER":
        st["user"] = rest
    elif kw == "HEALTHCHECK":
        st["healthcheck"] = (no, rest)
    elif kw == "COPY":
        words = rest.split()
        from_stage = None
        while words and words[0].startswith("--"):
            if words[0].startswith("--from="):
                from_stage = words[0][7:]
            words.pop(0)
        if len(words) < 2:
            problem(no, "COPY needs a source and a destination")
            continue
        *srcs, dest = words
        if from_stage is not None:
            if from_stage not in [s["name"] for s in stages[:-1]]:
                problem(no, f"COPY --from={from_stage}: no earlier stage of that name")
            continue
        if len(srcs) > 1 and not dest.endswith("/"):
            problem(no, "COPY of several sources needs a destination ending in /")
        dest_abs = os.path.normpath(dest if dest.startswith("/") else os.path.join(st["workdir"], dest))
        for src in srcs:
            if src == ".":
                st["context_at"] = dest_abs
                continue
            if not os.path.exists(os.path.join(repo, src)):
                problem(no, f"COPY source '{src}' does not exist in the repository")
            elif ignored(src):
                problem(no, f"COPY source '{src}' is excluded by {os.path.basename(ignore_file)}")
            target = os.path.join(dest_abs, os.path.basename(src)) if dest.endswith("/") else dest_abs
            st["copied"][os.path.normpath(target)] = src
    elif kw == "RUN":
        try:
            argv = json.loads(rest)
        except json.JSONDecodeError:
            problem(no, "RUN must be exec form (a JSON array) running one script of the repository")
            continue
        prog = argv[0]
        if not prog.startswith("/"):
            problem(no, f"RUN program '{prog}' is not an absolute path")
            continue
        src = st["copied"].get(os.path.normpath(prog))
        if src is None and st["context_at"] and prog.startswith(st["context_at"] + "/"):
            src = os.path.relpath(prog, st["context_at"])
        if src is None:
            problem(no, f"RUN program '{prog}' was not copied into this stage")
            continue
        full = os.path.join(repo, src)
        if not os.path.isfile(full):
            problem(no, f"RUN program '{prog}' is '{src}', which does not exist")
        elif not os.access(full, os.X_OK):
            problem(no, f"RUN program '{src}' is not executable")
        elif subprocess.run(["bash", "-n", full], capture_output=True).returncode != 0:
            problem(no, f"RUN program '{src}' has a shell syntax error")
    if kw in ("RUN", "CMD", "ENTRYPOINT") and re.search(r"\b(apt-get|apt|pip3?|curl|wget)\b", rest):
        problem(no, f"{kw}: packages come only through scripts/install-deps.sh")

if not stages:
    problem(1, "no FROM")
else:
    final = stages[-1]
    if final["name"] != "runtime":
        problem(final["line"], f"the final (default) stage is '{final['name']}', not 'runtime'")
    if final["user"] in (None, "root", "0"):
        problem(final["line"], "the runtime stage runs as root (no USER)")
    if final["healthcheck"] is None:
        problem(final["line"], "the runtime stage has no HEALTHCHECK")
    else:
        no, hc = final["healthcheck"]
        m = re.search(r"CMD\s+(\[.*\])\s*$", hc)
        if not m:
            problem(no, "HEALTHCHECK must be CMD in exec form")
        else:
            json.loads(m.group(1))

for p in problems:
    print(p)
print(f"check-dockerfile: {len(stages)} stages, {len(problems)} problem(s)")
sys.exit(1 if problems else 0)
