#!/usr/bin/env python3
"""Run one add-on test inside a Blender (CTest label `blender`; docs/testing.md).

    run.py --host debian|bpy|window --script test_x.py --zip build/knitshade_blender-0.1.0.zip
           --out build/test-output/blender/NAME [--bpy-python PYTHON]

Hosts:
  debian  Debian's Blender (3.4): blender -b --factory-startup --python-exit-code 1 --python SCRIPT
          ($BLENDER, else blender on PATH)
  window  the same Blender with a window, under xvfb-run -a (no -b): panels are drawn
  bpy     PyPI's bpy 5.0 module: PYTHON SCRIPT, PYTHON from --bpy-python, else
          $KNIT_BPY_PYTHON, else ${KNIT_BPY_VENV:-~/.cache/knitshade/bpy-5.0.1}/bin/python
          (scripts/setup-bpy.sh makes it)

The test gets an empty user folder (BLENDER_USER_SCRIPTS, _EXTENSIONS,
_CONFIG under OUT/user): it installs the zip there itself. It passes when
Blender exits 0, prints "knit-test: all checks passed", and its log holds no
Python traceback (errors in handlers, timers and panel draws are printed,
not raised). A host that is missing, or a test that prints "knit-test:
SKIP: why", exits 77 after saying plainly that the test did not run.
The whole log is kept in OUT/blender.log.
"""
import argparse
import os
import shutil
import signal
import subprocess
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
SKIP = 77


def default_bpy_python():
    venv = os.environ.get("KNIT_BPY_VENV") or os.path.join(os.path.expanduser("~"), ".cache", "knitshade",
                                                           "bpy-5.0.1")
    return os.path.join(venv, "bin", "python")


def find_host(args):
    """(command prefix, description) or (None, why not)."""
    if args.host == "bpy":
        for cand in (args.bpy_python, os.environ.get("KNIT_BPY_PYTHON"), default_bpy_python()):
            if cand and os.path.isfile(cand) and os.access(cand, os.X_OK):
                return [cand], "bpy module under " + cand
        return None, ("no Python with PyPI's bpy 5.0.1 (run scripts/setup-bpy.sh, or set KNIT_BPY_PYTHON, or "
                      "configure with -DKNIT_BPY_PYTHON=...)")
    blender = os.environ.get("BLENDER") or shutil.which("blender")
    if not blender:
        return None, "blender not found (Debian: apt-get install blender; or set BLENDER=/path/to/blender)"
    if args.host == "window":
        xvfb = shutil.which("xvfb-run")
        if not xvfb:
            return None, "xvfb-run not found (Debian: apt-get install xvfb xauth)"
        return [xvfb, "-a", "-s", "-screen 0 1600x1000x24", blender, "--factory-startup",
                "--window-geometry", "0", "0", "1600", "1000", "--no-window-focus",
                "--python-exit-code", "1", "--python"], "Blender with a window under xvfb-run"
    # --python-exit-code must come before --python: a failing script then
    # ends Blender with status 1 instead of 0.
    return [blender, "-b", "--factory-startup", "--python-exit-code", "1", "--python"], "Blender " + blender


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--host", choices=("debian", "bpy", "window"), required=True)
    ap.add_argument("--script", required=True)
    ap.add_argument("--zip", required=True)
    ap.add_argument("--out", required=True)
    ap.add_argument("--bpy-python", default="")
    ap.add_argument("--timeout", type=float, default=280)
    args = ap.parse_args()

    name = os.path.basename(args.script)
    prefix, what = find_host(args)
    if prefix is None:
        print("SKIPPED: %s in %s did NOT run: %s" % (name, args.host, what))
        return SKIP
    if not os.path.isfile(args.zip):
        print("FAIL: the add-on zip %s is missing (cmake --build build --target addon_zip)" % args.zip)
        return 1
    out = os.path.abspath(args.out)
    if os.path.isdir(out):
        shutil.rmtree(out)
    user = os.path.join(out, "user")
    env = dict(os.environ)
    for key, sub in (("BLENDER_USER_SCRIPTS", "scripts"), ("BLENDER_USER_EXTENSIONS", "extensions"),
                     ("BLENDER_USER_CONFIG", "config"), ("BLENDER_USER_DATAFILES", "datafiles")):
        env[key] = os.path.join(user, sub)
        os.makedirs(env[key])
    env["KNIT_ADDON_ZIP"] = os.path.abspath(args.zip)
    env["KNIT_TEST_OUT"] = out
    env["KNIT_SOURCE_DIR"] = ROOT
    env["KNIT_TEST_HOST"] = args.host
    env.pop("PYTHONPATH", None)  # nothing of the build tree: the zip is what is tested
    env.pop("PYTHONHOME", None)
    if args.host != "bpy":
        # Debian's Blender embeds the system's Python, which finds its prefix
        # from the first python3 on PATH: a pyenv or venv python there (pyenv
        # puts its own first for a pip-installed ctest) hides the system's
        # site-packages, numpy with them.
        keep = [p for p in env.get("PATH", "").split(os.pathsep)
                if p and not os.path.exists(os.path.join(p, "python3")) or p in ("/usr/bin", "/bin")]
        env["PATH"] = os.pathsep.join(["/usr/bin"] + [p for p in keep if p != "/usr/bin"])
    script = os.path.join(HERE, args.script)
    cmd = prefix + [script]
    print("%s: %s" % (what, " ".join(cmd)), flush=True)
    t0 = time.time()
    # its own process group, so a timeout ends Blender and Xvfb with it
    proc = subprocess.Popen(cmd, env=env, cwd=out, stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                            text=True, errors="replace", start_new_session=True)
    try:
        log, _ = proc.communicate(timeout=args.timeout)
        code = proc.returncode
    except subprocess.TimeoutExpired:
        os.killpg(proc.pid, signal.SIGKILL)
        log, _ = proc.communicate()
        code = "timeout after %.0f s" % args.timeout
    with open(os.path.join(out, "blender.log"), "w", encoding="utf-8") as f:
        f.write(log)
    lines = log.splitlines()
    for ln in lines:
        if ln.startswith("knit-test:"):
            print(ln)
    skip = [ln for ln in lines if ln.startswith("knit-test: SKIP")]
    tracebacks = [i for i, ln in enumerate(lines) if ln.startswith("Traceback")]
    passed = code == 0 and any(ln.startswith("knit-test: all checks passed") for ln in lines)
    if skip and code == 0 and not tracebacks:
        print("SKIPPED: %s in %s did NOT run: %s" % (name, args.host, skip[0].split("SKIP", 1)[1].strip(": ")))
        return SKIP
    if passed and not tracebacks:
        print("OK: %s in %s (%.1f s)" % (name, args.host, time.time() - t0))
        return 0
    if passed and tracebacks:
        print("FAIL: %s in %s passed its checks, but Blender's log holds a Python traceback:" % (name, args.host))
    else:
        print("FAIL: %s in %s: exit status %s" % (name, args.host, code))
    shown = set()
    for i in tracebacks[:3]:
        for j in range(max(0, i - 2), min(len(lines), i + 25)):
            if j not in shown:
                shown.add(j)
                print("  | " + lines[j])
    if not tracebacks:
        print("\n".join("  | " + ln for ln in lines[-60:]))
    print("(whole log: %s)" % os.path.join(out, "blender.log"))
    return 1


if __name__ == "__main__":
    sys.exit(main())
