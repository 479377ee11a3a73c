"""import flex3rpr without ROS: the core built alone (cmake -S src/core), PYTHONPATH=src and
F3R_LIBRARY naming the build folder, in an environment with nothing of the catkin workspace."""
import os
import subprocess
import sys

import pytest

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.realpath(__file__))))


@pytest.mark.skipif(os.environ.get("F3R_SANITIZED") == "1",
                    reason="the plain build is the same code; the sanitized suite covers it")
def test_the_module_imports_from_the_core_built_alone(tmp_path):
    build = str(tmp_path / "core")
    subprocess.run(["cmake", "-S", os.path.join(ROOT, "src", "core"), "-B", build,
                    "-DCMAKE_BUILD_TYPE=Release"], check=True, stdout=subprocess.DEVNULL)
    subprocess.run(["cmake", "--build", build, "--target", "flex3rpr_py", "-j2"], check=True,
                   stdout=subprocess.DEVNULL)
    env = {"PATH": "/usr/bin:/bin", "HOME": os.environ.get("HOME", "/tmp"),
           "PYTHONPATH": os.path.join(ROOT, "src"), "F3R_LIBRARY": build}
    code = ("import flex3rpr\n"
            "s = flex3rpr.Sim('%s')\n"
            "print(s.step([10.0, 0, 0, 0, 0, 0], periods=10).t)\n"
            "try:\n    import flex3rpr.msg\nexcept ImportError:\n    print('no messages')\n"
            % os.path.join(ROOT, "config", "scenes", "rest.yaml"))
    out = subprocess.run([sys.executable, "-c", code], env=env, check=True,
                         capture_output=True, text=True).stdout.split()
    assert out == ["0.01", "no", "messages"]
