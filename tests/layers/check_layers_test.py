#!/usr/bin/env python3
"""tools/check_layers.py against trees made here: it must refuse each wrong include and pass
the allowed ones, reading the layer table of the repository's own docs/design.md."""
import os
import shutil
import subprocess
import sys
import tempfile
import unittest

SOURCE = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
CHECK = os.path.join(SOURCE, "tools", "check_layers.py")


class CheckLayers(unittest.TestCase):
    def setUp(self):
        self.root = tempfile.mkdtemp(prefix="keel-layers-")
        os.makedirs(os.path.join(self.root, "docs"))
        shutil.copy(os.path.join(SOURCE, "docs", "design.md"), os.path.join(self.root, "docs"))
        for header in ["core/time.h", "proto/job.h", "worker/mapping/voxel.h",
                       "worker/pipeline/stage.h", "worker/stages/map/artifacts.h",
                       "worker/stages/map/stage.h", "storage/store.h"]:
            self.write(header, "#pragma once\n")

    def tearDown(self):
        shutil.rmtree(self.root)

    def write(self, path, text):
        full = os.path.join(self.root, path)
        os.makedirs(os.path.dirname(full), exist_ok=True)
        with open(full, "w") as f:
            f.write(text)

    def run_check(self):
        done = subprocess.run([sys.executable, CHECK, self.root], capture_output=True, text=True)
        return done.returncode, done.stdout

    def test_allowed_includes_pass(self):
        self.write("worker/slam/solver.cc", '#include "core/time.h"\n#include <vector>\n')
        self.write("worker/stages/compare/stage.cc",
                   '#include "worker/stages/map/artifacts.h"\n#include "worker/pipeline/stage.h"\n')
        self.write("server/routes.cc", '#include "storage/store.h"\n#include <boost/beast.hpp>\n')
        code, out = self.run_check()
        self.assertEqual(code, 0, out)

    def test_an_algorithm_including_another_is_refused(self):
        self.write("worker/slam/solver.cc", '#include "core/time.h"\n#include "worker/mapping/voxel.h"\n')
        code, out = self.run_check()
        self.assertEqual(code, 1)
        self.assertIn('worker/slam/solver.cc:2: includes "worker/mapping/voxel.h" (algorithms)', out)

    def test_a_stage_reaching_into_another_stage_is_refused(self):
        self.write("worker/stages/compare/stage.cc", '#include "worker/stages/map/stage.h"\n')
        code, out = self.run_check()
        self.assertEqual(code, 1)
        self.assertIn("worker/stages/compare/stage.cc:1", out)

    def test_an_upward_include_is_refused(self):
        self.write("proto/options.cc", '#include "worker/pipeline/stage.h"\n')
        code, out = self.run_check()
        self.assertEqual(code, 1)
        self.assertIn("proto/options.cc:1", out)
        self.assertIn("'contracts' may not use", out)

    def test_only_processes_use_asio(self):
        self.write("storage/store.cc", "#include <boost/asio.hpp>\n")
        code, out = self.run_check()
        self.assertEqual(code, 1)
        self.assertIn("storage/store.cc:1: includes <boost/asio.hpp>", out)

    def test_the_repository_itself_passes(self):
        done = subprocess.run([sys.executable, CHECK, SOURCE], capture_output=True, text=True)
        self.assertEqual(done.returncode, 0, done.stdout)


if __name__ == "__main__":
    unittest.main()
