#!/usr/bin/env python3
"""Tests of tools/benchmarks.py's page merge: a run replaces only the sections of its parts.

    python3 tools/test_benchmarks.py        (or: python3 -m unittest discover -s tools)

Standard library only; needs no binary, scenes or peers.
"""
import os
import sys
import unittest

sys.dont_write_bytecode = True
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import benchmarks as b  # noqa: E402


def page(**parts):
    return b.merge_page("", {k: f"## {k}\n\nMeasured on DAY-{k}.\n\n| a |\n|--:|\n| {v} |\n" for k, v in parts.items()})


class MergePage(unittest.TestCase):
    def test_a_run_replaces_its_parts_and_keeps_the_others_verbatim(self):
        old = page(renders=1, peers=2, large=3)
        new = b.merge_page(old, {"peers": "## peers\n\nMeasured on DAY-new.\n\n| a |\n|--:|\n| 20 |\n"})
        got = b.split_sections(new)
        self.assertEqual(got["renders"], b.split_sections(old)["renders"])
        self.assertEqual(got["large"], b.split_sections(old)["large"])
        self.assertIn("| 20 |", got["peers"])
        self.assertNotIn("| 2 |", new)
        self.assertIn("DAY-renders", new)
        self.assertIn("DAY-large", new)

    def test_sections_follow_the_part_order_and_parts_never_run_say_how(self):
        new = b.merge_page("", {"large": "## Large\n\nx\n", "renders": "## Renders\n\ny\n"})
        self.assertEqual(list(b.split_sections(new)), ["renders", "large"])
        self.assertLess(new.index("part:renders"), new.index("part:large"))
        self.assertIn("Not run yet: `tools/benchmarks.sh --parts viewer`", new)
        self.assertTrue(new.startswith("# Benchmarks\n"))

    def test_merging_nothing_new_is_a_fixed_point(self):
        old = page(renders=1, e2e=2, viewer=3)
        self.assertEqual(b.merge_page(old, {}), old)
        self.assertEqual(b.merge_page(b.merge_page(old, {}), {}), old)

    def test_unknown_parts_and_subsections_survive(self):
        old = page(renders=1) + "\n" + b.section("retired", "## Retired\n\n| kept |\n") + "trailing text\n"
        old = old.replace("| 1 |", "| 1 |\n\n### A subsection\n\n<!-- a comment -->\n| 11 |")
        new = b.merge_page(old, {"peers": "## Peers\n\nz\n"})
        got = b.split_sections(new)
        self.assertIn("| kept |", got["retired"])
        self.assertIn("### A subsection", got["renders"])
        self.assertIn("| 11 |", got["renders"])

    def test_the_measured_line_names_date_machine_and_noise(self):
        run = {"cmdline": "tools/benchmarks.sh --parts viewer", "machine": "CPU X", "bin": "wp", "digest": "abc",
               "built": "then", "head": "1234567", "rustc": "rustc 1"}
        quiet = b.measured_line(run, {"date": "2026-01-02 03:04 UTC", "load_before": 0.1, "load_after": 0.2,
                                      "busy_mean": 0.01, "busy_max": 0.02})
        self.assertIn("Measured on 2026-01-02 03:04 UTC", quiet)
        self.assertIn("CPU X", quiet)
        self.assertIn("quiet machine", quiet)
        noisy = b.measured_line(run, {"date": "d", "load_before": 5.0, "load_after": 0.2, "busy_mean": 0.5,
                                      "busy_max": 0.9})
        self.assertIn("noisy machine", noisy)

    def test_the_checked_in_page_is_made_of_sections(self):
        path = os.path.join(b.REPO, "BENCHMARKS.md")
        with open(path) as f:
            text = f.read()
        sections = b.split_sections(text)
        self.assertTrue(sections, "BENCHMARKS.md has no part sections")
        for name, sec in sections.items():
            self.assertIn("Measured on ", sec, f"section {name} says when it was measured")
        self.assertEqual(b.merge_page(text, {}), text, "BENCHMARKS.md is what a merge of nothing leaves")


if __name__ == "__main__":
    unittest.main()
