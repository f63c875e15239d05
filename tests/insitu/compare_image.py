# Compares a rendered PNG with its baseline the way VTK's regression tests do (vtkTesting:
# vtkImageDifference with +-2 px shift tolerance and 3x3 averaging, threshold 0.15). On failure
# vtkTesting leaves the new image and a difference image (<name>.diff.png) in OUT_DIR.
# Usage: pvpython compare_image.py NEW.png BASELINE.png OUT_DIR
import sys

from vtkmodules.vtkTestingRendering import vtkTesting

new, baseline, out_dir = sys.argv[1:4]
testing = vtkTesting()
for arg in ("-T", out_dir, "-V", baseline):
    testing.AddArgument(arg)
result = testing.RegressionTest(new, 0.15)
print()
if result != vtkTesting.PASSED:
    print("image differs from %s: new image and difference image in %s" % (baseline, out_dir))
    sys.exit(1)
print("image matches %s" % baseline)
