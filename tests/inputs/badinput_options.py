"""The bad-input corpus, continued: files that are not text (encodings, binary data, a directory, a
FIFO, a device, too large, unreadable names) given as a spec, scenario or profile, and the
command-line options (the output folder, runs, seeds, spreads, steps)."""

from __future__ import annotations

import random

from .badinput_cases import DIRECTORY, FIFO, LAG, LOOP, SPEC, Case, patch_argv
from .badinput_inputs import BP, MP, SC, SC_ARGV, spec_for_profile
from .badinput_toml import dumps

GOOD_SPEC = dumps(LAG)
GOOD_SCENARIO = 'duration_s = 1.0\n[initial]\ntheta_deg = 1.0\n'


def _garbage(seed: int, n: int = 512) -> bytes:
    rng = random.Random(seed)
    return bytes(rng.randrange(128, 256) for _ in range(n))


# what a file can be instead of UTF-8 TOML, and the field the line names ("" for the whole file)
CONTENTS = {
    "latin1-comment": (("# r\xe9glage du chariot\n" + GOOD_SPEC).encode("latin-1"), ""),
    "latin1-value": (GOOD_SPEC.replace('"bench-recommended"', '"r\xe9glage"', 1).encode("latin-1"), ""),
    "utf16": (GOOD_SPEC.encode("utf-16"), ""),
    "garbage-1": (_garbage(1), ""),
    "garbage-2": (_garbage(2, 4096), ""),
    "nul-bytes": (b"name = \"x\"\n\x00\x00\x00\n", ""),
    "elf-header": (b"\x7fELF\x02\x01\x01\x00" + bytes(56), ""),
    "png-header": (b"\x89PNG\r\n\x1a\n" + bytes(32), ""),
    "not-toml": (b"{\"name\": \"json, not toml\"}\n", ""),
    "broken-table": (GOOD_SPEC.encode() + b"\n[broken\n", ""),
    "duplicate-key": (GOOD_SPEC.encode() + b"name = \"again\"\n", ""),
    "deep-nesting": (b"a = " + b"[" * 100_000 + b"\n", ""),
    "too-large": (b"# " + b"x" * (1 << 20) + b"\n", ""),
}
KINDS = {"directory": DIRECTORY, "fifo": FIFO, "symlink-loop": LOOP}


def file_cases() -> list[Case]:
    out = []
    for name, (data, field) in CONTENTS.items():
        out.append(Case(f"file-spec-{name}", patch_argv(), SPEC, field, {"spec.toml": data}))
        out.append(Case(f"file-scenario-{name}", SC_ARGV, SC, field, {"sc.toml": data}))
        out.append(Case(f"file-machine-{name}", patch_argv(), MP, field, {**spec_for_profile("machine", MP),
                                                                         "m.toml": data}))
        out.append(Case(f"file-bench-{name}", patch_argv(), BP, field, {**spec_for_profile("bench", BP),
                                                                       "b.toml": data}))
    for name, kind in KINDS.items():
        out.append(Case(f"kind-spec-{name}", patch_argv(), SPEC, "", {"spec.toml": kind}))
        out.append(Case(f"kind-scenario-{name}", SC_ARGV, SC, "", {"sc.toml": kind}))
        for field, path in (("machine", MP), ("bench", BP)):
            out.append(Case(f"kind-{field}-{name}", patch_argv(), SPEC, field,
                            {**spec_for_profile(field, path), path.removeprefix("@TMP@/"): kind}))
    long_name = "@TMP@/" + "s" * 300 + ".toml"
    out += [
        Case("spec-empty-file", patch_argv(), SPEC, "name", {"spec.toml": b""}),
        Case("spec-comments-only", patch_argv(), SPEC, "name", {"spec.toml": b"# nothing here\n"}),
        Case("spec-missing-file", patch_argv(), SPEC, ""),
        Case("spec-dev-null", patch_argv("/dev/null"), "/dev/null", ""),
        Case("spec-long-name", patch_argv(long_name), long_name, ""),
        Case("spec-under-a-file", patch_argv("@TMP@/afile/spec.toml"), "@TMP@/afile/spec.toml", "",
             {"afile": b"x"}),
        Case("spec-unknown-shipped", patch_argv("no-such-design"), "no-such-design", ""),
        Case("spec-huge-int", patch_argv(), SPEC, "plant.M",
             {"spec.toml": GOOD_SPEC.replace("M = 3.552", "M = 123456789012345678901234567890")}),
        Case("scenario-empty-file", SC_ARGV, SC, "duration_s", {"sc.toml": b""}),
        Case("scenario-missing-file", SC_ARGV, SC, ""),
        Case("scenario-unknown-shipped", SC_ARGV[:3] + ("hold-forever",) + SC_ARGV[4:], "hold-forever", ""),
    ]
    unreadable = (("missing-file", "machine", "@TMP@/nope.toml"), ("missing-file", "bench", "@TMP@/nope.toml"),
                  ("unknown-id", "machine", "eniac"), ("unknown-id", "bench", "mit-1950"),
                  ("device", "machine", "/dev/null"), ("long-path", "bench", "@TMP@/x" * 60 + ".toml"),
                  ("empty-name", "machine", ""), ("under-a-file", "bench", "@TMP@/spec.toml/b.toml"))
    for name, field, path in unreadable:
        out.append(Case(f"profile-{field}-{name}", patch_argv(), SPEC, field, spec_for_profile(field, path)))
    return out


def _opt(cmd: str, name: str, argv: tuple[str, ...], source: str, usage: bool = True, **kw) -> Case:
    return Case(f"option-{cmd}-{name}", argv, source, kw.pop("field", ""), {"spec.toml": GOOD_SPEC,
                                                                            "sc.toml": GOOD_SCENARIO,
                                                                            **kw.pop("files", {})},
                usage=usage, **kw)


def _out_cases(cmd: str, argv, files=None) -> list[Case]:
    """The output folder: empty, a file, under a file, in /proc, names too long, clashes."""
    files = files or {}
    opt = "DIR" if cmd == "examples" else "-o"
    long_name = "@TMP@/" + "o" * 300
    long_path = "@TMP@/" + "/".join(["d" * 200] * 25)
    cases = [
        ("empty", "", "''", False), ("proc", "/proc/patchgen-out", "/proc/patchgen-out", False),
        ("sys", "/sys/patchgen-out", "/sys/patchgen-out", False),
        ("dev", "/dev/patchgen/out", "/dev/patchgen/out", False),
        ("dev-null", "/dev/null", "/dev/null", False), ("under-file", "@TMP@/afile/sub", "@TMP@/afile/sub", False),
        ("deep-under-file", "@TMP@/afile/a/b", "@TMP@/afile/a/b", False),
        ("long-name", long_name, long_name, False), ("long-path", long_path, long_path, False),
        ("a-file", "@TMP@/afile", "-o" if opt == "-o" else "DIR", True),
    ]
    out = []
    for name, target, source, usage in cases:
        out.append(_opt(cmd, f"out-{name}", argv(target), source, usage=usage, field="" if usage else opt,
                        files={"afile": b"x", **files}, out=target))
    return out


def option_cases() -> list[Case]:
    sim = lambda *extra, out="@TMP@/out": ("simulate", SPEC, "--scenario", SC, "-o", out, *extra)  # noqa: E731
    pat = lambda *extra, out="@TMP@/out": ("patch", SPEC, "-o", out, "--no-predict", *extra)  # noqa: E731
    out = _out_cases("patch", lambda o: pat(out=o)) + _out_cases("simulate", lambda o: sim(out=o))
    out += _out_cases("examples", lambda o: ("examples", o))
    out += _out_cases("swingup", lambda o: ("swingup", SPEC, "-o", o))
    out += _out_cases("recommend", lambda o: ("recommend", SPEC, "-o", o, "--runs", "1"))
    out += _out_cases("spice", lambda o: ("spice", SPEC, "--scenario", SC, "-o", o))
    for cmd, argv, existing in (("patch", pat(), ("pots.csv",)), ("simulate", sim(), ("summary.json",)),
                                ("swingup", ("swingup", SPEC, "-o", "@TMP@/out"), ("manoeuvre.json",)),
                                ("recommend", ("recommend", SPEC, "-o", "@TMP@/out"), ("recommendation.md",)),
                                ("spice", ("spice", SPEC, "--scenario", SC, "-o", "@TMP@/out"), ("patch.cir",)),
                                ("examples", ("examples", "@TMP@/out"), ("designs/thesis-ch5.toml",))):
        opt = "DIR" if cmd == "examples" else "-o"
        out.append(_opt(cmd, "out-exists", argv, f"@TMP@/out/{existing[0]}", usage=False, field=opt,
                        existing=existing))
        forced = argv + ("--force",)
        out.append(_opt(cmd, "out-directory-in-the-way", forced, f"@TMP@/out/{existing[0]}", usage=False,
                        field=opt, existing=(existing[0] + "/",)))
    out.append(_opt("examples", "out-file-for-folder", ("examples", "@TMP@/out", "--force"), "@TMP@/out/designs",
                    usage=False, field="DIR", existing=("designs",)))
    bad = {
        "simulate": [("runs-zero", sim("--runs", "0"), "--runs"), ("runs-negative", sim("--runs", "-1"), "--runs"),
                     ("runs-word", sim("--runs", "many"), "--runs"), ("runs-float", sim("--runs", "2.5"), "--runs"),
                     ("runs-huge", sim("--runs", "10000000"), "--runs"),
                     ("seed-negative", sim("--seed", "-1"), "--seed"),
                     ("seed-huge", sim("--seed", str(2**63)), "--seed"),
                     ("seed-word", sim("--seed", "lucky"), "--seed"), ("seed-float", sim("--seed", "1.5"), "--seed"),
                     ("scenario-missing", ("simulate", SPEC, "-o", "@TMP@/out"), "--scenario"),
                     ("no-such-option", sim("--colour", "red"), "--colour")],
        "patch": [("runs-zero", ("patch", SPEC, "-o", "@TMP@/out", "--runs", "0"), "--runs"),
                  ("runs-huge", ("patch", SPEC, "-o", "@TMP@/out", "--runs", "10001"), "--runs"),
                  ("no-out", ("patch", SPEC), "-o")],
        "spice": [(f"step-{v}", ("spice", SPEC, "--scenario", SC, "-o", "@TMP@/out", "--step", v), "--step")
                  for v in ("nan", "inf", "0", "-1", "1", "fast")]
        + [(f"tolerance-{v}", ("spice", SPEC, "--scenario", SC, "-o", "@TMP@/out", "--tolerance", v), "--tolerance")
           for v in ("nan", "inf", "-0.1", "2", "tight")],
        "swingup": [(f"hold-{v}", ("swingup", SPEC, "-o", "@TMP@/out", "--hold", v), "--hold")
                    for v in ("nan", "inf", "-inf", "0", "1e9", "long")]
        + [(f"force-limit-{v}", ("swingup", SPEC, "-o", "@TMP@/out", "--force-limit", v), "--force-limit")
           for v in ("nan", "inf", "0", "1e6", "strong")]
        + [("seed-negative", ("swingup", SPEC, "-o", "@TMP@/out", "--seed", "-1"), "--seed"),
           ("strategy", ("swingup", SPEC, "-o", "@TMP@/out", "--strategy", "kick"), "--strategy")],
        "recommend": [("runs-zero", ("recommend", SPEC, "-o", "@TMP@/out", "--runs", "0"), "--runs"),
                      ("runs-huge", ("recommend", SPEC, "-o", "@TMP@/out", "--runs", "100001"), "--runs"),
                      ("seed-negative", ("recommend", SPEC, "-o", "@TMP@/out", "--seed", "-5"), "--seed")],
        "sweep": [("workers", ("sweep", SPEC, "--workers", "100"), "--workers"),
                  ("runs-zero", ("sweep", SPEC, "--runs", "0"), "--runs")],
    }
    for cmd, items in bad.items():
        out += [_opt(cmd, name, argv, source) for name, argv, source in items]
    # refused by patchgen's own checks: "patchgen: OPTION: what is wrong"
    mine = [
        ("simulate", "spread-200", sim("--spread", "200%"), "--spread"),
        ("simulate", "spread-zero", sim("--spread", "0"), "--spread"),
        ("simulate", "spread-nan", sim("--spread", "nan"), "--spread"),
        ("simulate", "spread-inf", sim("--spread", "inf%"), "--spread"),
        ("simulate", "spread-word", sim("--spread", "some"), "--spread"),
        ("simulate", "spread-empty", sim("--spread", ""), "--spread"),
        ("simulate", "vary-unknown", sim("--spread", "10%", "--vary", "M,mass"), "--vary"),
        ("simulate", "vary-empty", sim("--spread", "10%", "--vary", ","), "--vary"),
        ("simulate", "runs-absurd", ("simulate", SPEC, "--scenario", "hold-120s", "-o", "@TMP@/out",
                                     "--runs", "1000000"), "--runs"),
        ("recommend", "runs-absurd", ("recommend", SPEC, "-o", "@TMP@/out", "--runs", "100000",
                                      "--scenario", "@TMP@/long.toml"), "--runs"),
        ("spice", "step-too-fine", ("spice", SPEC, "--scenario", "hold-120s", "-o", "@TMP@/out",
                                    "--step", "1e-5"), "--step"),
        ("sweep", "by-zero", ("sweep", SPEC, "--by", "0%"), "--by"),
        ("sweep", "by-100", ("sweep", SPEC, "--by", "100%"), "--by"),
        ("sweep", "by-nan", ("sweep", SPEC, "--by", "nan"), "--by"),
        ("sweep", "by-word", ("sweep", SPEC, "--by", "lots"), "--by"),
        ("sweep", "vary-unknown", ("sweep", SPEC, "--vary", "M,q"), "--vary"),
        ("sweep", "runs-absurd", ("sweep", SPEC, "--scenario", "@TMP@/long.toml", "--runs", "10000"), "--runs"),
    ]
    long = {"long.toml": 'duration_s = 10000.0\n'}
    out += [_opt(cmd, name, argv, source, usage=False, files=long) for cmd, name, argv, source in mine]
    sweep_sc = [("sweep", "scenario-missing", ("sweep", SPEC, "--scenario", "@TMP@/nope.toml"), "@TMP@/nope.toml"),
                ("sweep", "scenario-outside-track", ("sweep", SPEC, "--scenario", "@TMP@/far.toml"), "@TMP@/far.toml")]
    far = {"far.toml": 'duration_s = 1.0\n[initial]\ns = 2.0\n'}
    out += [_opt(cmd, name, argv, source, usage=False, files=far, field="initial.s" if "far" in source else "")
            for cmd, name, argv, source in sweep_sc]
    return out
