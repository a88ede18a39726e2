#!/usr/bin/env python3
"""readme_test.py — every example in README.md runs as written on demo.db (issue 17, item 6).

Usage: readme_test.py SQLITE3_SHELL MODULE SOURCE_DIR [BVH_DIR]      (ctest: sql/readme)

Builds demo.db the way `./run.sh demo` does (sql/build_demo.sh, with the real corpus when
BVH_DIR exists), then runs, each on a fresh copy of it, in a directory where `./build/affect`
is the module under test and `sql/`, `examples/` and `python/` are the checkout's:

- every ```sql block, through the sqlite3 shell (`-bail`): it must finish without an error;
- every transcript (a ``` block whose lines start with `$ sqlite3 …` or `sqlite> `): its
  statements (`sqlite> ` and `   ...> ` lines) through the shell, and the output must be the
  lines the README shows, exactly (an error as `Runtime error: …`), unless the block is marked
  abridged by a `…` line, when only unexpected errors fail;
- every ```python block with Debian's /usr/bin/python3 (PYTHONPATH=python): it must exit 0;
  when the block right after it is plain output, its output must be that;
- every ```sh block that queries demo.db (starts with `sqlite3 demo.db`): its sqlite3 commands,
  through bash; the other sh blocks install or build, and run.sh itself runs them.

It also checks that docs/reference.md's contents list names every function and module the
module registers.

A block that needs something the machine lacks is skipped with a message: the real corpus's
rows (when BVH_DIR is absent, a block naming `dataset-1_` or `bandai-namco` is skipped), a
Python that cannot load extensions, or sqlite-vec (MODULE's folder/npm, where run.sh test
installs it). Prints one line per block; exits 1 if any failed.
"""
import os
import re
import shutil
import subprocess
import sys
import tempfile

PYTHON = "/usr/bin/python3"
TIMEOUT = 600  # seconds per block: the slowest (affect_crossval on the corpus) takes about 60


def blocks(readme):
    """(line number, language, text) of every fenced block."""
    out, lang, start, buf = [], None, 0, []
    for n, line in enumerate(readme.splitlines(), 1):
        if line.startswith("```"):
            if lang is None:
                lang, start, buf = line[3:].strip(), n, []
            else:
                out.append((start, lang, "\n".join(buf) + "\n"))
                lang = None
        elif lang is not None:
            buf.append(line)
    return out


def transcript(text):
    """[(statement, expected output lines)] of a `sqlite> ` transcript."""
    steps = []
    for line in text.splitlines():
        if line.startswith("$ "):
            continue
        if line.startswith("sqlite> "):
            steps.append([line[len("sqlite> "):], []])
        elif line.startswith("   ...> ") and steps and not steps[-1][1]:
            steps[-1][0] += "\n" + line[len("   ...> "):]
        elif steps:
            steps[-1][1].append(line)
    return steps


def sqlite_commands(text):
    """The commands of a sh block that run the sqlite3 shell (a line ending in a backslash
    continues); the others (a Blender window, say) are a person's, and their tests are
    elsewhere (client/blender)."""
    cmds, cur = [], ""
    for line in text.splitlines():
        cur += line + "\n"
        if not line.endswith("\\"):
            if cur.startswith("sqlite3 "):
                cmds.append(cur)
            cur = ""
    return "".join(cmds)


def run(cmd, cwd, stdin=None, env=None):
    p = subprocess.run(cmd, cwd=cwd, input=stdin, env=env, capture_output=True, text=True,
                       timeout=TIMEOUT)
    return p.returncode, p.stdout, p.stderr


def shell_error(line):
    # the shell prints "Runtime error near line 3: …" when reading a script, "Runtime error: …"
    # at its prompt (what the README's transcripts show)
    return re.sub(r"^(Runtime|Parse) error near line \d+:", r"\1 error:", line)


def registered(shell, module):
    """The names of the functions and modules the module registers (those present once it is
    loaded and not before)."""
    q = "SELECT name FROM pragma_function_list UNION SELECT name FROM pragma_module_list"
    before = set(run([shell, ":memory:", q], "/")[1].split())
    after = set(run([shell, ":memory:", "-cmd", ".load " + module, q], "/")[1].split())
    return sorted(after - before)


def reference_contents(shell, module, src):
    """docs/reference.md's contents list (its first paragraph starting "Contents:") names every
    function and module: the number of those it does not name, each printed."""
    with open(os.path.join(src, "docs", "reference.md"), encoding="utf-8") as f:
        text = f.read()
    start = text.index("\nContents:")
    contents = text[start:text.index("\n\n", start)]
    names = registered(shell, module)
    missing = [n for n in names if not re.search(r"\b%s\b" % re.escape(n), contents)]
    for n in missing:
        print("FAIL docs/reference.md: the contents list does not name %s" % n)
    print("docs/reference.md contents: %d functions and modules, %d missing"
          % (len(names), len(missing)))
    return len(missing)


def main():
    if len(sys.argv) < 4:
        print(__doc__)
        return 2
    shell, module, src = sys.argv[1], os.path.abspath(sys.argv[2]), os.path.abspath(sys.argv[3])
    corpus = sys.argv[4] if len(sys.argv) > 4 and os.path.isdir(sys.argv[4]) else None
    module_file = module if module.endswith(".so") else module + ".so"
    with open(os.path.join(src, "README.md"), encoding="utf-8") as f:
        readme = f.read()
    work = tempfile.mkdtemp(prefix="readme-")
    try:
        base = os.path.join(work, "base")
        os.mkdir(base)
        code, out, err = run(["bash", os.path.join(src, "sql/build_demo.sh"), shell, module, src]
                             + ([corpus] if corpus else []), base)
        if code:
            print("FAIL: building demo.db:\n" + out[-2000:] + err[-2000:])
            return 1
        db = os.path.join(base, "demo.db")
        py_ok = run([PYTHON, "-c", "import sqlite3; sqlite3.connect(':memory:')"
                     ".enable_load_extension(True)"], work)[0] == 0 if os.path.exists(PYTHON) \
            else False
        env = dict(os.environ, PYTHONPATH=os.path.join(src, "python"),
                   SQLITE_AFFECT_PATH=module_file)
        all_blocks = blocks(readme)
        failures = ran = skipped = 0
        for i, (line, lang, text) in enumerate(all_blocks):
            first = text.lstrip().splitlines()[0] if text.strip() else ""
            kind = None
            if lang == "sql":
                kind = "sql"
            elif lang == "python":
                kind = "python"
            elif lang == "sh" and first.startswith("sqlite3 demo.db"):
                kind = "sh"
            elif lang == "" and (first.startswith("$ sqlite3") or first.startswith("sqlite> ")):
                kind = "transcript"
            if kind is None:
                continue
            where = "README.md:%d (%s)" % (line, kind)
            if not corpus and re.search(r"dataset-1_|bandai-namco", text):
                print("SKIP %s: needs the real corpus (../shared absent)" % where)
                skipped += 1
                continue
            vec0 = os.path.join(os.path.dirname(module_file), "npm")
            if "vec0" in text and not os.path.isdir(vec0):
                print("SKIP %s: sqlite-vec is not installed (%s; run.sh test installs it)"
                      % (where, vec0))
                skipped += 1
                continue
            if kind == "python" and not py_ok:
                print("SKIP %s: %s cannot load extensions" % (where, PYTHON))
                skipped += 1
                continue
            cwd = os.path.join(work, "b%d" % line)
            os.mkdir(cwd)
            shutil.copy(db, cwd)
            os.mkdir(os.path.join(cwd, "build"))
            os.symlink(module_file, os.path.join(cwd, "build", "affect.so"))
            if os.path.isdir(vec0):
                os.symlink(vec0, os.path.join(cwd, "build", "npm"))
            for d in ("sql", "examples", "python", "tests"):
                os.symlink(os.path.join(src, d), os.path.join(cwd, d))
            problem = None
            if kind == "sql":
                load = [] if re.search(r"^\.load ", text, re.M) else ["-cmd", ".load ./build/affect"]
                code, out, err = run([shell, "-bail"] + load + ["demo.db"], cwd, text)
                if code or err.strip():
                    problem = (err or out).strip()
            elif kind == "sh":
                code, out, err = run(["bash", "-e", "-c", sqlite_commands(text)], cwd, env=env)
                if code or re.search(r"error", err, re.I):
                    problem = (err or out).strip()
            elif kind == "python":
                code, out, err = run([PYTHON, "-"], cwd, text, env)
                if code:
                    problem = err.strip()
                elif i + 1 < len(all_blocks) and all_blocks[i + 1][1] == "" and \
                        all_blocks[i + 1][0] <= line + text.count("\n") + 4:
                    want = all_blocks[i + 1][2]
                    if "…" not in want and out.strip() != want.strip():
                        problem = "output:\n%s\nthe README shows:\n%s" % (out.strip(), want.strip())
            else:
                steps = transcript(text)
                abridged = "…" in text
                head = [l for l in text.splitlines() if l.startswith("$ ")]
                cmd = [shell, "demo.db"]
                if head:
                    m = re.match(r"\$ sqlite3 demo\.db -cmd '([^']*)'$", head[0])
                    if not m:
                        problem = "cannot read the command line: " + head[0]
                    else:
                        cmd += ["-cmd", m.group(1)]
                else:
                    cmd += ["-cmd", ".load ./build/affect"]
                if problem is None:
                    script = "".join(s + "\n" if s.startswith(".") else
                                     s.rstrip().rstrip(";") + ";\n" for s, _ in steps)
                    code, out, err = run(cmd, cwd, script)
                    # compared without trailing blanks (column mode pads its last column)
                    got = [shell_error(l).rstrip() for l in (out + err).splitlines()]
                    want = [l.rstrip() for _, o in steps for l in o]
                    if abridged:
                        bad = [l for l in got if "error" in l and l not in want]
                        if bad:
                            problem = "\n".join(bad)
                    elif got != want:
                        problem = "output:\n%s\nthe README shows:\n%s" % ("\n".join(got),
                                                                       "\n".join(want))
            ran += 1
            if problem:
                failures += 1
                print("FAIL %s:\n  %s" % (where, problem.replace("\n", "\n  ")))
            else:
                print("ok   %s" % where)
        print("README examples: %d run, %d failed, %d skipped" % (ran, failures, skipped))
        failures += reference_contents(shell, module, src)
        return 1 if failures else 0
    finally:
        shutil.rmtree(work, ignore_errors=True)


if __name__ == "__main__":
    sys.exit(main())
