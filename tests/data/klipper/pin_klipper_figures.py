"""How klipper_figures.json was made: Klipper's own functions, run OUTSIDE shapefmu on the recordings.

Never run by the tests (they read the JSON). Klipper is GPL; this script only calls it. To redo:

    cd /path/to/klipper   # a checkout of Klipper3d/klipper at the commit in its COMMIT file
    python /path/to/pin_klipper_figures.py tests/data/recordings tests/data/klipper > klipper_figures.json

For every CSV in the folders: Klipper's parse_log (scripts/calibrate_shaper.py), then
ShaperCalibrate.find_best_shaper with the defaults calibrate_shaper.py uses (scv 5, no max_smoothing):
the pick and the shaper fitted for each of zv, mzv, ei, 2hump_ei, 3hump_ei; fit_shaper of zvd over its
default scan; and fit_shaper of each of the six at three frequencies (its fitted one, 0.8 and 1.25
times it, rounded to 0.1 Hz). Every figure is printed at full precision (JSON floats are repr).
"""
import json, os, sys

sys.path.insert(0, os.path.join(os.getcwd(), "klippy"))
sys.path.insert(0, os.path.join(os.getcwd(), "scripts"))
import calibrate_shaper  # noqa: E402
from extras import shaper_calibrate  # noqa: E402

SIX = ["zv", "mzv", "zvd", "ei", "2hump_ei", "3hump_ei"]


def row(r):
    return {"name": r.name, "freq": float(r.freq), "vibrations": float(r.vibrs), "smoothing": float(r.smoothing),
            "max_accel": float(r.max_accel), "score": float(r.score)}


def main():
    helper = shaper_calibrate.ShaperCalibrate(printer=None)
    out = {"klipper_commit": open("COMMIT").read().strip() if os.path.exists("COMMIT") else os.popen("git rev-parse HEAD").read().strip(),
           "made_by": "tests/data/klipper/pin_klipper_figures.py (its docstring)", "files": {}}
    for folder in sys.argv[1:]:
        for name in sorted(os.listdir(folder)):
            if not name.endswith(".csv"):
                continue
            path = os.path.join(folder, name)
            best, fitted = helper.find_best_shaper(calibrate_shaper.parse_log(path), scv=5.)
            zvd = helper.fit_shaper("zvd", calibrate_shaper.parse_log(path), None, None, 5., None, None, None, None)[0]
            by_name = {r.name: r for r in fitted}
            by_name["zvd"] = zvd
            points = []
            for shaper in SIX:
                f0 = float(by_name[shaper].freq)
                for f in (f0, round(0.8 * f0, 1), round(1.25 * f0, 1)):
                    r = helper.fit_shaper(shaper, calibrate_shaper.parse_log(path), [f], None, 5., None, None, None,
                                          None)[0]
                    points.append(row(r))
            out["files"][name] = {"pick": row(best), "fitted": [row(r) for r in fitted] + [row(zvd)], "points": points}
    print(json.dumps(out, indent=1))


if __name__ == "__main__":
    main()
