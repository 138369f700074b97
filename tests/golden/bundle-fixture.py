
# ======== gloffuse part: units.py ========
# The fixture's base: imported by both other modules, so bundled first.
import math

SCALE = 2.0


def area(radius):
    return math.pi * radius * radius * SCALE

# ======== gloffuse part: shapes.py ========
import os



def describe(radius):
    return "%s: %.3f at scale %g, sqrt %g" % (os.sep, area(radius), SCALE, math.sqrt(radius))

# ======== gloffuse part: job.py ========
import json



def main(document_text):
    radius = json.loads(document_text)["radius"]
    print(describe(radius), area(radius))
