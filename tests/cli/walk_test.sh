#!/usr/bin/env bash
# The walkthrough end to end on a small scene: a scene file, a calibration on the headless
# renderer, a short real-rendered path with screenshots, and a simulated path in which the
# barrier and exact selectors must hold the budget against the calibrated noise; then a second
# scene with a textured mesh (the spider of assimp's OBJ models, its images beside its .tom).
set -u
tools="$1"; walk="$2"; data="$3"; src="$(cd "$(dirname "$0")/../.." && pwd)"
work="$(mktemp -d)"; trap 'rm -rf "$work"' EXIT
. "$(dirname "$0")/check.sh"
"$tools/tombuild" "$data/meshes/fandisk.off" "$data/meshes/cow.off" "$data/meshes/elephant.off" -o "$work/meshes" -q -j 2 || { echo "tombuild failed"; exit 1; }
check "a scene file is made" "$walk" --make-scene "$work/scene.txt" --meshes "$work"/meshes/*.tom --instances 60 --seed 3
check "the scene file lists meshes and instances" test "$(grep -c '^instance' "$work/scene.txt")" -eq 60
check "calibration on the headless renderer" "$walk" --scene "$work/scene.txt" --calibrate "$work/calibration.txt" --width 320 --height 240
check "the calibration file has every key" bash -c "for k in t_init_ms t_final_ms t_setup_ms t_tri_ms t_vert_ms t_pix_ms safety_ms noise_rel; do grep -q \"^\$k \" '$work/calibration.txt' || exit 1; done"

# the budget follows this machine: a quarter of what the calibrated model says full detail
# costs to extract and render along the path (a fixed 6 ms was only 2.9x below full detail on a
# fast stretch of the machine, too light a scenario for the checks below)
check "a simulated path at full detail" "$walk" --scene "$work/scene.txt" --calibration "$work/calibration.txt" --simulate --selector none \
  --frames 300 --budget-ms 1000 --out "$work/full"
budget="$(/usr/bin/python3 -c "
import csv
rows = list(csv.DictReader(open('$work/full/frames-none.csv')))
print('%.3f' % (sum(float(r['render_ms']) for r in rows) / len(rows) / 4))")"
echo "budget: $budget ms (a quarter of full detail along the path)"

# a short real-rendered path
check "a real-rendered path" "$walk" --scene "$work/scene.txt" --calibration "$work/calibration.txt" --selector none,exact,barrier \
  --frames 30 --budget-ms "$budget" --width 320 --height 240 --out "$work/real" --json --quality-every 10
for s in none exact barrier; do
  check "frames-$s.csv has a row per frame" test "$(wc -l < "$work/real/frames-$s.csv")" -eq 31
done
# the image against full detail: "none" draws full detail, so its frames are the reference's
check "every 10th frame is scored against full detail (SSIM, PSNR)" /usr/bin/python3 -c "
import csv, json
runs = {r['selector']: r for r in json.load(open('$work/real/summary.json'))}
for name, r in runs.items():
    assert r['quality_frames'] == 3, (name, r['quality_frames'])
    assert 0 < r['ssim_min'] <= r['ssim_mean'] <= 1 and r['psnr_mean'] > 0, (name, r)
assert runs['none']['ssim_mean'] == 1.0 and runs['none']['psnr_mean'] == 99.0, runs['none']
assert runs['exact']['ssim_mean'] < 1.0 and runs['exact']['psnr_mean'] < 99.0, runs['exact']
rows = list(csv.DictReader(open('$work/real/quality.csv')))
assert len(rows) == 9 and {r['selector'] for r in rows} == set(runs), rows
"
check "the measured frames and their references are kept" test "$(ls "$work"/real/quality/reference-*.png | wc -l)" -eq 3 -a "$(ls "$work"/real/quality/exact-*.png | wc -l)" -eq 3
# the menu: exact with the whole menu against exact on TOM levels alone, on the same path
check "a real path with imposters, and with levels alone" "$walk" --scene "$work/scene.txt" --calibration "$work/calibration.txt" --selector exact,exact-levels \
  --frames 30 --budget-ms "$budget" --width 320 --height 240 --out "$work/menu" --quality-every 10
# a fit may put flat shading's cost on its triangles or on its vertices, and a quad's on
# its setup or its pixels: each way's cost for a typical draw must be positive; the depth
# meshes' costs above the floors calibration puts on them (1e-9 and 1e-6 ms)
check "the calibration fits flat shading, quads, depth meshes and refreshes" /usr/bin/python3 -c "
k = dict((l.split()[0], float(l.split()[1])) for l in open('$work/calibration.txt') if len(l.split()) == 2 and not l.startswith('#'))
assert k['flat_t_tri_ms'] + k['flat_t_vert_ms'] > 0, k
assert k['imposter_t_setup_ms'] + 1000 * k['imposter_t_pix_ms'] > 0, k
assert k['refresh_t_setup_ms'] > 0, k
assert k['meshed_t_tri_ms'] > 1e-9 and k['meshed_refresh_t_setup_ms'] > 1e-6, k
assert k['textured_t_tri_ms'] + k['textured_t_vert_ms'] > 0, k
"
check "levels alone draw no imposter; the menu's imposters are counted and their renewals bounded" /usr/bin/python3 -c "
import csv, json
runs = {r['selector']: r for r in json.load(open('$work/menu/summary.json'))}
lv, menu = runs['exact-levels'], runs['exact']
assert lv['representations'] == 'levels' and menu['representations'] == 'all', (lv, menu)
assert lv['imposters_drawn_mean'] == 0 and lv['imposter_refreshes_mean'] == 0 and lv['flat_objects_mean'] == 0, lv
assert 0 <= menu['imposter_refreshes_mean'] <= menu['imposters_drawn_mean'], menu
assert lv['meshed_imposters_mean'] == 0 and 0 <= menu['meshed_imposters_mean'] <= menu['imposters_drawn_mean'], (lv, menu)
rows = list(csv.DictReader(open('$work/menu/frames-exact.csv')))
assert all(int(r['imposter_refreshes']) <= int(r['imposters']) and int(r['meshed_imposters']) <= int(r['imposters']) for r in rows), rows
for r in (lv, menu): assert 0 < r['ssim_mean'] < 1, r
"
check "--representations levels is a menu of levels for every selector" bash -c "'$walk' --scene '$work/scene.txt' --calibration '$work/calibration.txt' --selector exact --representations levels --frames 10 --budget-ms '$budget' --width 320 --height 240 --out '$work/lv' --json | /usr/bin/python3 -c 'import json, sys; r = [json.loads(l) for l in sys.stdin if l.startswith(\"{\")]; assert r and all(x[\"imposters_drawn_mean\"] == 0 for x in r), r'"
# the selectors take the path frame by frame, or with --sequential one after another: either way
# each writes its own rows, frame 0 to the last
for mode in "" --sequential; do
  check "a real path ${mode:-interleaved}: a row a frame for each selector" bash -c "'$walk' --scene '$work/scene.txt' --calibration '$work/calibration.txt' --selector static,exact --frames 12 --budget-ms '$budget' --width 320 --height 240 --out '$work/order$mode' $mode && for s in static exact; do test \"\$(cut -d, -f1 '$work/order$mode'/frames-\$s.csv | tail -n +2 | tr '\\n' ' ')\" = '0 1 2 3 4 5 6 7 8 9 10 11 ' || exit 1; done"
done
check "--quality-every with --simulate is a usage error" bash -c "'$walk' --scene '$work/scene.txt' --calibration '$work/calibration.txt' --simulate --quality-every 5 --out '$work/q' --frames 10; test \$? -eq 2"
check "the summary has the documented keys" /usr/bin/python3 -c "
import json
runs = json.load(open('$work/real/summary.json'))
assert [r['selector'] for r in runs] == ['none', 'exact', 'barrier'], runs
for r in runs:
    for k in ['selector', 'frames', 'budget_ms', 'frame_ms', 'over_budget_fraction', 'prediction_error', 'drawn_triangles_mean', 'visible_triangles_mean']:
        assert k in r, (k, r)
    assert set(r['frame_ms']) >= {'mean', 'max', 'std'}
none, exact = runs[0], runs[1]
assert exact['drawn_triangles_mean'] < none['drawn_triangles_mean'], (exact, none)   # the budget cut triangles
assert none['frame_ms']['mean'] > $budget, none                                    # full detail does not fit
"
check "screenshots at A, B, C, normal and LOD views, non-empty and different" /usr/bin/python3 -c "
import csv, json
import matplotlib.image as im
shot_frame = json.load(open('$work/real/summary.json'))[0]['viewpoint_frames']
for s in ['exact', 'barrier']:
    rows = list(csv.DictReader(open('$work/real/frames-%s.csv' % s)))
    for v in 'ABC':
        a = im.imread('$work/real/shots/%s-%s.png' % (s, v)); b = im.imread('$work/real/shots/%s-%s-lod.png' % (s, v))
        assert a.shape == (240, 320, 4) and b.shape == a.shape, a.shape
        drawn = int(float(rows[shot_frame[v]]['drawn_triangles']))
        if drawn == 0:
            continue  # nothing drawn at that frame (B looks at the few far objects; a noisy budget may drop all)
        # what was drawn shows: pixels away from the background (the corner's colour; at B the
        # far objects may cover only a few), and the LOD view recolours them
        covered = (abs(a[..., :3] - a[0, 0, :3]).max(axis=2) > 0.05).sum()
        assert covered > 0, ('blank picture', s, v, drawn)
        assert (abs(a[..., :3] - b[..., :3]).max(axis=2) > 0.05).sum() >= min(20, covered // 2), ('LOD view identical', s, v, drawn, covered)
"
check "plots of the run" "$src/scripts/plot-walk.py" "$work/real" --format png
check "the plots exist" test -s "$work/real/frame-times.png" -a -s "$work/real/triangles.png"

# the simulated path: every selector; barrier and exact hold the budget. Its noise is the
# calibration's at a fixed 10% of the frame (the measured one follows the machine's load, and
# the frames over budget with it)
sed 's/^noise_rel .*/noise_rel 0.1/' "$work/calibration.txt" > "$work/calibration-sim.txt"
check "a simulated path" "$walk" --scene "$work/scene.txt" --calibration "$work/calibration-sim.txt" --simulate --selector all --frames 300 \
  --budget-ms "$budget" --out "$work/sim" --json
check "barrier and exact hold the budget against simulated noise: none over 1.1x, at most 10% over" /usr/bin/python3 -c "
import csv
for s in ['barrier', 'exact']:
    rows = list(csv.DictReader(open('$work/sim/frames-%s.csv' % s)))
    assert len(rows) == 300
    measured = [float(r['measured_ms']) for r in rows]
    assert max(measured) <= 1.1 * $budget, (s, max(measured))
    over = sum(m > $budget for m in measured)
    assert over <= 30, (s, over)
    assert sum(measured) / len(measured) <= $budget, (s, sum(measured) / len(measured))
    # the noise is real (bounded by the safety allowance, not by the prediction): many frames take
    # longer than predicted, and the runtime's correction, which follows the measured frames, errs too
    over_prediction = sum(m > float(r['predicted_ms']) + 1e-6 for m, r in zip(measured, rows))
    assert over_prediction > 30, (s, over_prediction)
"
check "at a quarter of full detail's cost, exact draws under a third of its triangles" /usr/bin/python3 -c "
import json
runs = {r['selector']: r for r in json.load(open('$work/sim/summary.json'))}
assert runs['exact']['drawn_triangles_mean'] < runs['none']['drawn_triangles_mean'] / 3, runs['exact']
"
# tomview: a whole glTF scene (29 meshes of 34 parts, 67 instances, 34 materials) drawn from its .tom, a draw per part
view="$(dirname "$walk")/tomview"
"$tools/tombuild" "$data/assimp/glTF2/2CylinderEngine-glTF-Binary/2CylinderEngine.glb" -o "$work/engine" -q --no-error-curve
check "tomview draws every instance of the scene" bash -c "'$view' '$work/engine/2CylinderEngine.tom' -o '$work/engine-full.png' --width 320 --height 240 | grep -q '67 instances of 29 meshes, 34 materials'"
check "tomview at 10% and in LOD colours" "$view" "$work/engine/2CylinderEngine.tom" -f 0.1 --lod-colors -o "$work/engine-10.png" --width 320 --height 240
check "the pictures show the scene in its materials' colours, and differ" /usr/bin/python3 -c "
import matplotlib.image as im
a = im.imread('$work/engine-full.png'); b = im.imread('$work/engine-10.png')
assert a.shape == (240, 320, 4) and b.shape == a.shape, a.shape
assert a[..., :3].std() > 0.05, 'blank picture'
blue = (a[..., 2] > a[..., 0] + 0.2).sum()   # the engine's blue and teal parts
assert blue > 100, blue
assert (abs(a[..., :3] - b[..., :3]).max(axis=2) > 0.05).sum() > 500
"
# a GLB whose texture's PNG is stored in the .tom: drawn texture-mapped, the right way up (the
# logo's blue sky above its green hills on the box's faces; untextured, the white material is grey)
"$tools/tombuild" "$data/assimp/glTF2/BoxTextured-glTF-Binary/BoxTextured.glb" -o "$work/box" -q --no-error-curve
check "tomview draws the box with its stored image" "$view" "$work/box/BoxTextured.tom" -o "$work/box.png" --width 400 --height 300
check "the picture shows the logo upright" /usr/bin/python3 -c "
import matplotlib.image as im, numpy as np
a = im.imread('$work/box.png')[..., :3]
blue = (a[..., 2] > a[..., 0] + 0.15) & (a[..., 2] > a[..., 1] + 0.05)
green = (a[..., 1] > a[..., 2] + 0.1) & (a[..., 1] > a[..., 0] + 0.05)
assert blue.sum() > 1000 and green.sum() > 1000, (blue.sum(), green.sum())
rows = np.arange(a.shape[0])[:, None]
assert (rows * blue).sum() / blue.sum() < (rows * green).sum() / green.sum(), 'the hills are above the sky'
"
# --fraction 0 stops at the usable floor (tombuild's stored 1% error bound); --below-floor goes on
# to the coarsest level of the chain, as tominfo lists both
"$tools/tombuild" "$data/assimp/OBJ/WusonOBJ.obj" -o "$work/wuson" -q
check "tomview --fraction 0 draws the usable floor, with --below-floor the coarsest level" /usr/bin/python3 -c "
import json, re, subprocess
info = json.loads(subprocess.run(['$tools/tominfo', '$work/wuson/WusonOBJ.tom', '--json'], capture_output=True, text=True, check=True).stdout)['meshes'][0]
def drawn(*extra):
    out = subprocess.run(['$view', '$work/wuson/WusonOBJ.tom', '-f', '0', '-o', '$work/wuson.png', '--width', '160', '--height', '120', *extra], capture_output=True, text=True, check=True).stdout
    return int(re.search(r'; (\d+) of \d+ triangles drawn', out).group(1))
usable, coarsest = drawn(), drawn('--below-floor')
assert info['min_triangles'] < info['usable_floor']['triangles'], info
assert (usable, coarsest) == (info['usable_floor']['triangles'], info['min_triangles']), (usable, coarsest, info)
"
check "tomview on a file that is not a .tom exits 1" bash -c "'$view' '$data/meshes/fandisk.off' -o '$work/x.png'; test \$? -eq 1"
check "the noise test draws one frame again and again and reports its spread" /usr/bin/python3 -c "
import json, subprocess
out = subprocess.run(['$walk', '--scene', '$work/scene.txt', '--calibration', '$work/calibration.txt', '--noise-test', '40',
                      '--budget-ms', '$budget', '--width', '320', '--height', '240', '--json'], capture_output=True, text=True, check=True).stdout
j = json.loads(out)
assert j['renders'] == 40 and j['triangles'] > 0 and j['objects'] > 0, j
assert j['median_ms'] > 0 and j['std_percent'] > 0, j                          # real frames vary
# the frame is the one exact planned at the budget, the model corrected on 10 frames there: it
# takes about the budget (its reserve and allowance below it, the renderer's noise around it;
# the calibration ran minutes before on this shared machine, and a change of load in between
# moved a CI run's median to 1.34x the budget, where the unplanned frame takes 4x)
assert 0.3 * $budget <= j['median_ms'] <= 1.5 * $budget, (j['median_ms'], $budget)
assert j['p5_percent'] <= 100 <= j['p95_percent'], j
lo, hi = j['block10_percent']
assert 0 < lo <= hi, j                                                        # means of 10 in a row
assert -1 <= j['lag1_autocorrelation'] <= 1, j
"
check "the noise test needs the renderer" bash -c "'$walk' --scene '$work/scene.txt' --calibration '$work/calibration.txt' --noise-test 40 --simulate 2>/dev/null; test \$? -eq 2"
check "a missing scene is an error" bash -c "! '$walk' --scene '$work/none.txt' --calibration '$work/calibration.txt' 2>/dev/null"

# a textured scene: the spider (four parts, each its own image) among fandisks
tex="$work/textured"
"$tools/tombuild" "$data/assimp/OBJ/spider.obj" "$data/meshes/fandisk.off" -o "$tex/meshes" -q -j 2 || { echo "tombuild failed"; exit 1; }
cp "$data"/assimp/OBJ/*.jpg "$tex/meshes/"
check "a textured scene file is made" "$walk" --make-scene "$tex/scene.txt" --meshes "$tex"/meshes/*.tom --instances 20 --seed 5
check "a real path on the textured scene" "$walk" --scene "$tex/scene.txt" --calibration "$work/calibration.txt" --selector none,exact,exact-levels \
  --frames 20 --budget-ms "$budget" --width 320 --height 240 --out "$tex/run" --quality-every 10
check "full detail is texture-mapped; the menu draws the spiders texture-mapped, the levels alone plain" /usr/bin/python3 -c "
import json
runs = {r['selector']: r for r in json.load(open('$tex/run/summary.json'))}
assert runs['none']['ssim_mean'] == 1.0 and runs['none']['textured_objects_mean'] > 0, runs['none']
assert runs['exact']['textured_objects_mean'] > 0 and runs['exact-levels']['textured_objects_mean'] == 0, runs
"
# one image missing is reported by name and its part drawn plain; one that is not an image
# stops the run with an error naming it
mv "$tex/meshes/SpiderTex.jpg" "$tex/SpiderTex.jpg.kept"
check "a missing image is reported by name and the run goes on" bash -c "'$walk' --scene '$tex/scene.txt' --calibration '$work/calibration.txt' --selector exact --frames 10 --width 160 --height 120 --json 2>'$tex/missing.err' >/dev/null && grep -q 'SpiderTex.jpg' '$tex/missing.err'"
printf 'not a jpeg' > "$tex/meshes/SpiderTex.jpg"
check "an unreadable image is an error naming it" bash -c "'$walk' --scene '$tex/scene.txt' --calibration '$work/calibration.txt' --selector exact --frames 10 --width 160 --height 120 2>'$tex/broken.err' >/dev/null; test \$? -eq 1 && grep -q 'SpiderTex.jpg' '$tex/broken.err'"
mv "$tex/SpiderTex.jpg.kept" "$tex/meshes/SpiderTex.jpg"
echo "$passed passed, $fail failed"
[ "$fail" -eq 0 ]
