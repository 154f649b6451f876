#!/usr/bin/env python3
"""Fail when a commit after BASE has a subject longer than 72 characters.

Why: `git log --oneline`, `git shortlog` and most review tools cut a subject at about 72
characters, so the rest of a long one is lost where people read it; the evidence belongs in the
body. Commits up to BASE are history and keep their subjects.

Usage: .ci/check_commit_subjects.py [--base COMMIT] [--repo DIR]
Needs only git and the Python standard library, so CI runs it before setting anything up.
"""

from __future__ import annotations

import argparse
import subprocess
import sys

#: The last commit not checked: HEAD when the check was added (older subjects run long).
BASE = "56d0c862096c856b3f383837dc739e19f6bcc5a8"
MAX_SUBJECT = 72


def git(repo: str, *args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run(["git", "-C", repo, *args], capture_output=True, text=True, check=False)


def subjects_after(repo: str, base: str) -> list[tuple[str, str]]:
    """(short hash, subject) of every commit reachable from HEAD and not from `base`."""
    log = git(repo, "log", "--format=%h%x00%s", f"{base}..HEAD")
    if log.returncode != 0:
        raise SystemExit(f"check_commit_subjects: git log failed: {log.stderr.strip()}")
    return [tuple(line.split("\0", 1)) for line in log.stdout.splitlines() if line]  # type: ignore[misc]


def too_long(subjects: list[tuple[str, str]], limit: int = MAX_SUBJECT) -> list[str]:
    """One line per subject over `limit` characters."""
    return [
        f"{sha}: {len(subject)} characters: {subject}" for sha, subject in subjects if len(subject) > limit
    ]


def base_problem(repo: str, base: str) -> tuple[str, bool] | None:
    """Why the commits after `base` cannot be listed, and whether that is a failure; None if they can.
    A tarball or a shallow clone without the base is not this check's to judge; a full history
    without it was rewritten, and BASE must move."""
    if git(repo, "rev-parse", "--git-dir").returncode != 0:
        return f"{repo} is not a git checkout; nothing to check", False
    if git(repo, "cat-file", "-e", f"{base}^{{commit}}").returncode == 0:
        return None
    shallow = git(repo, "rev-parse", "--is-shallow-repository").stdout.strip() == "true"
    if shallow:
        return f"the base commit {base[:12]} is not in this shallow clone; nothing checked", False
    return (
        f"the base commit {base[:12]} is not in this repository's history; update BASE in .ci/check_commit_subjects.py",
        True,
    )


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--base", default=BASE, help="the last commit not checked (default: %(default)s)")
    parser.add_argument("--repo", default=".", help="the repository (default: the current folder)")
    args = parser.parse_args(argv)
    problem = base_problem(args.repo, args.base)
    if problem is not None:
        text, fails = problem
        print(f"check_commit_subjects: {text}", file=sys.stderr)
        return 1 if fails else 0
    subjects = subjects_after(args.repo, args.base)
    bad = too_long(subjects)
    for line in bad:
        print(f"check_commit_subjects: subject over {MAX_SUBJECT} characters: {line}", file=sys.stderr)
    if not bad:
        print(
            f"check_commit_subjects: {len(subjects)} commit subject(s) after {args.base[:12]} within "
            f"{MAX_SUBJECT} characters"
        )
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
