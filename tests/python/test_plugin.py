# SPDX-License-Identifier: GPL-3.0-or-later
"""Tests of what the CAD plugins share (client/python/gridshell_client/plugin.py): the background
call a UI loop polls. Its result after a cancel is the contract both plugins rely on when a user
presses Esc (Blender) or Cancel (FreeCAD) while the answer is on its way: nothing changes.

    python3 -m unittest discover -s tests/python -t tests/python -v
"""

import base64
import threading
import unittest

import gridshell_testing as T  # noqa: F401,N812 (puts client/python on sys.path)

import gridshell_client as gs
from gridshell_client import plugin


def finished(call, seconds=30):
    if not call.wait(seconds):
        raise AssertionError("the background call did not finish in %d s" % seconds)
    return call


class BackgroundCallTest(unittest.TestCase):
    def test_result_and_progress(self):
        def work(progress, cancel):
            progress(gs.Progress("distance maps", 0.5, ""))
            return {"answer": 42}

        call = finished(plugin.BackgroundCall(work))
        self.assertTrue(call.done)
        self.assertFalse(call.cancelled)
        self.assertEqual(call.progress.stage, "distance maps")
        self.assertEqual(call.result(), {"answer": 42})
        self.assertGreaterEqual(call.finished, call.started)

    def test_error_is_raised_again(self):
        def work(progress, cancel):
            raise gs.InvalidInput("options.resolution: must be 0 (adaptive) or 8..1000", "INVALID_ARGUMENT")

        call = finished(plugin.BackgroundCall(work))
        with self.assertRaises(gs.InvalidInput) as raised:
            call.result()
        self.assertIn("options.resolution", str(raised.exception))

    def test_cancel_after_the_answer_came_discards_it(self):
        # The work finished, but the UI had not taken the result when the user cancelled.
        call = finished(plugin.BackgroundCall(lambda progress, cancel: {"members": 9}))
        call.cancel()
        self.assertTrue(call.cancelled)
        with self.assertRaises(gs.Cancelled):
            call.result()

    def test_cancel_reaches_the_work(self):
        started, seen = threading.Event(), threading.Event()

        def work(progress, cancel):
            started.set()
            if cancel.wait(30):  # what the client does while it waits for the daemon
                seen.set()
                raise gs.Cancelled("cancelled by the client", "CANCELLED")
            return "not cancelled"

        call = plugin.BackgroundCall(work)
        self.assertTrue(started.wait(30))
        self.assertFalse(call.done)
        call.cancel()
        finished(call, 5)
        self.assertTrue(seen.is_set(), "the work's own flag was not set")
        with self.assertRaises(gs.Cancelled):
            call.result()


if __name__ == "__main__":
    unittest.main()


class AutomaticGridTest(unittest.TestCase):
    """An automatic layout's grid, as both plugins show it, says what kind of surface it covers."""

    def test_a_disk_a_ring_and_a_closed_surface(self):
        self.assertEqual(plugin.automatic_grid({"columns": 3, "rows": 2}), "3 x 2")
        self.assertEqual(plugin.automatic_grid({"columns": 3, "rows": 2, "surface": "disk"}), "3 x 2")
        self.assertEqual(plugin.automatic_grid({"columns": 14, "rows": 1, "surface": "ring"}),
                         "14 x 1 round the ring")
        self.assertEqual(plugin.automatic_grid({"columns": 2, "rows": 2, "surface": "closed"}),
                         "6 faces x 2 x 2")


class JoiningNoteTest(unittest.TestCase):
    """The status line's note on a layout run's joining, as both plugins print it."""

    def test_joined_seams_give_the_patches_alone_and_the_bolts_force(self):
        note = plugin.joining_note({"seams_joined": True, "diagonal": 50.0, "rms_before_joining": 0.25,
                                    "max_bolt_force": 4332.0, "force_unit": "N"})
        self.assertEqual(note, "; patches alone RMS 0.25 (0.500 %); largest bolt force 4332 N")

    def test_a_failed_join_says_why_and_nothing_else_says_nothing(self):
        failed = {"seams_joined": False, "joined_with_notches": {"converged": False,
                                                                  "termination": "joining the patches failed: x"}}
        self.assertEqual(plugin.joining_note(failed), " (joining the patches failed: x)")
        self.assertEqual(plugin.joining_note({"seams_joined": False}), "")


class JoinedPatchResultsTest(unittest.TestCase):
    """Each patch's share of the joined whole, shaped as its own result, for drawing per patch."""

    def result(self, joined=True):
        obj = ("# whole\no north-west-g0\nv 0 0 0\nv 1 0 0\nv 1 1 0\nf 1 2 3\n"
               "o P2-g0\nv 5 0 0\nv 6 0 0\nv 6 1 0\nf 4 5 6\nf 6 5 4\n")
        rods = [{"centerline": [[0, 0, 0], [1, 0, 0]], "deviation": [0.1, 0.2]},
                {"centerline": [[5, 0, 0], [6, 0, 0]], "deviation": [0.3, 0.4]}]
        return {
            "deployment": {"seams_joined": joined, "rods": rods, "rod_patches": ["north-west", "P2"],
                           "joined_with_notches": {"rms": 0.2},
                           "patches": [{"name": "north-west", "joined_rms": 0.15}, {"name": "P2", "joined_rms": 0.35}]},
            "views": [{"name": "deployed.obj", "content": base64.b64encode(obj.encode()).decode()}],
        }

    def test_each_patch_gets_its_objects_renumbered_and_its_joined_rods(self):
        parts = plugin.joined_patch_results(self.result())
        self.assertEqual(sorted(parts), ["P2", "north-west"])
        p2 = parts["P2"]
        self.assertEqual(p2["deployment"]["rods"], [self.result()["deployment"]["rods"][1]])
        self.assertEqual(p2["deployment"]["with_notches"], {"rms": 0.35, "max_deviation": 0.4})
        obj = gs.files_of(p2)["deployed.obj"].decode()
        self.assertEqual(obj, "o P2\nv 5 0 0\nv 6 0 0\nv 6 1 0\nf 1 2 3\nf 3 2 1\n")
        west = gs.files_of(parts["north-west"])["deployed.obj"].decode()
        self.assertIn("v 1 1 0\nf 1 2 3\n", west)

    def test_seams_not_joined_give_nothing(self):
        self.assertEqual(plugin.joined_patch_results(self.result(joined=False)), {})
        self.assertEqual(plugin.joined_patch_results({}), {})
