#!/usr/bin/env python3
"""Checks a survey export against what the browser showed and clicked (survey_browser.py --record).

    /usr/bin/python3 check_subset.py RUN EXPORT SCREENS PER CONTROLS

RUN is the served run folder (its key.csv maps configuration ids to animation names), EXPORT the
folder `experiments survey export` wrote, SCREENS the --record file of one participant's session,
PER the real questions of that participant's balanced subset and CONTROLS the control questions.
Asserts that exactly one participant answered the PER real questions and the CONTROLS controls
and completed; that the subset is smaller than the questionnaire; that no question was answered
twice; that every exported answer carries the two sides its screen showed, in the order shown
(the export's `swapped` undone), and the side clicked; and that every control showed one
animation on both sides and kept its click. Used by scripts/survey-e2e.sh and
scripts/study-e2e.sh. Prints one summary line; exits non-zero on the first mismatch.
"""

import csv
import json
import os
import sys


def rows(path):
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def main():
    run, export, screens = sys.argv[1], sys.argv[2], sys.argv[3]
    per, ncontrols = int(sys.argv[4]), int(sys.argv[5])
    name_of = {r["id"]: r["name"] for r in rows(os.path.join(run, "key.csv"))}
    canonical = {
        r["question"]: (name_of[r["left"]], name_of[r["right"]])
        for r in rows(os.path.join(export, "questions.csv"))
    }
    with open(screens) as f:
        seen = {s["position"]: s for s in json.load(f)}
    responses = rows(os.path.join(export, "responses.csv"))
    controls = rows(os.path.join(export, "controls.csv"))
    participants = rows(os.path.join(export, "participants.csv"))
    # One participant, who answered the N real questions of the subset and the controls.
    assert len(participants) == 1, participants
    p = participants[0]
    want_total = str(per + ncontrols)
    assert (p["answered"], p["total"], p["completed"]) == (want_total, want_total, "1"), p
    assert len(seen) == per + ncontrols, (
        f"the browser answered {len(seen)} screens, not {per + ncontrols}"
    )
    assert len(responses) == per, f"{len(responses)} answers exported, not {per}"
    assert len({r["question"] for r in responses}) == per, "a question answered twice"
    assert len(canonical) > per, f"the subset is the whole questionnaire ({len(canonical)} questions)"
    flip = {"L": "R", "R": "L", "N": "N"}
    for r in responses:
        assert r["participant"] == p["participant"], r
        screen = seen[int(r["order"])]
        left, right = canonical[r["question"]]
        shown = (right, left) if r["swapped"] == "1" else (left, right)
        assert (screen["left"], screen["right"]) == shown, (r, screen, (left, right))
        want = flip[screen["clicked"]] if r["swapped"] == "1" else screen["clicked"]
        assert r["response"] == want, (r, screen)
    assert len(controls) == ncontrols, controls
    for c in controls:
        screen = seen[int(c["order"])]
        assert screen["left"] == screen["right"] == c["name"], (c, screen)
        assert c["response"] == screen["clicked"], (c, screen)
    swapped = sum(r["swapped"] == "1" for r in responses)
    print(
        f"   {per} answers of {len(canonical)} questions, {swapped} shown swapped, "
        f"{ncontrols} controls: every answer as its screen showed it"
    )


if __name__ == "__main__":
    sys.exit(main())
