#!/usr/bin/env bash
# Command-line contracts of tombuild, tominfo and tomextract:
# exit codes (0 ok, 1 some inputs failed, 2 usage), a batch goes on past a bad input, outputs
# are byte-identical whatever -j, a failed input leaves no file (no .tom, no temporary), and
# tomextract writes readable OBJ/PLY levels.
set -u
tools="$1"; data="$2"; src="$(cd "$(dirname "$0")/../.." && pwd)"
work="$(mktemp -d)"; trap 'rm -rf "$work"' EXIT
. "$(dirname "$0")/check.sh"

[ -s "$data/meshes/bunny00.off" ] || { echo "samples missing: run scripts/fetch-samples.sh"; exit 1; }

# a batch folder: good meshes, a broken glTF, a file with no triangles
mkdir -p "$work/in/sub"
cp "$data/meshes/fandisk.off" "$data/meshes/cow.off" "$work/in/"
cp "$data/assimp/OBJ/spider.obj" "$data/assimp/OBJ/spider.mtl" "$work/in/sub/"
cp "$data/assimp/glTF2/IndexOutOfRange/IndexOutOfRange.gltf" "$data/assimp/glTF2/IndexOutOfRange/IndexOutOfRange.bin" "$work/in/sub/"
cp "$data/assimp/OBJ/testpoints.obj" "$work/in/"

# every hostile file of the first fuzzing run among good ones: the good ones convert, each bad one
# is named with its reason, no signal ends the run, and the summary is written
mkdir -p "$work/hostile"
cp "$data/meshes/fandisk.off" "$work/hostile/a.off"
cp "$data/meshes/cow.off" "$work/hostile/c.off"
cp "$src"/tests/data/hostile/* "$work/hostile/"
check "a batch with the fuzzing run's files converts the good ones and exits 1" expect_exit 1 "$tools/tombuild" "$work/hostile" -o "$work/hostile-out" --report-json "$work/hostile-reports"
check "the good inputs of that batch are converted" test -s "$work/hostile-out/a.tom" -a -s "$work/hostile-out/c.tom" -a -s "$work/hostile-out/M-obj-comment-inside-face.tom"
check "every converted file of that batch is valid" bash -c "for f in '$work'/hostile-out/*.tom; do '$tools/tominfo' \"\$f\" >/dev/null || exit 1; done"
check "each hostile input is named with its reason" bash -c "n=\$(grep -c '^error: .*hostile/[A-Z][0-9]*-' '$work/stderr'); test \"\$n\" -eq 16"
check "the batch's summary lists the converted meshes" test "$(wc -l < "$work/hostile-reports/summary.csv")" -eq 6
# its two zero-area triangles share identical corners: welded, nothing is left (an error naming
# the mesh); with --no-weld the copies are kept and it converts
check "the coincident-copies OBJ welds to nothing: an error naming its mesh" bash -c "'$tools/tombuild' '$work/hostile/E-coincident-neighbours.obj' -o '$work/hostile-w' 2>&1 | grep -q \"mesh 'E-coincident-neighbours' has no non-degenerate triangle\""
check "tombuild -v --no-weld on the coincident-copies OBJ ends" timeout 20 "$tools/tombuild" "$work/hostile/E-coincident-neighbours.obj" -o "$work/hostile-v" -v --no-weld

# a batch survives any one input: each converts in a worker process with a time and a memory
# limit. One batch, run one input at a time, whose first worker crashes (SIGSEGV sent to it
# mid-report), whose second hangs (SIGSTOP sent to it: it never ends unless --timeout ends it),
# whose third needs more than --max-memory (bunny00's report in 400 MB), with two good inputs
# after them. (Skipped under AddressSanitizer, which needs the whole address space: tombuild
# sets no memory limit there.)
if [ -z "${TOM_SANITIZED:-}" ]; then
mkdir -p "$work/isolate"
cp "$data/meshes/fandisk.off" "$work/isolate/a-crashes.off"
cp "$data/meshes/fandisk.off" "$work/isolate/b-hangs.off"
cp "$data/meshes/bunny00.off" "$work/isolate/c-hungry.off"
cp "$src/tests/fuzz/corpus/import_off_fuzz/cube.off" "$work/isolate/d-good.off"
cp "$src/tests/fuzz/corpus/import_ply_fuzz/tetra-le.ply" "$work/isolate/e-good.ply"
"$tools/tombuild" "$work/isolate" -o "$work/isolate-out" --report --max-memory 400 --timeout 8 -j 1 -q >"$work/isolate.out" 2>"$work/isolate.err" &
batch=$!
worker_after() {  # the batch's first worker whose pid is not $1
  for _ in $(seq 500); do
    local p; p=$(pgrep -P "$batch" | head -1)
    if [ -n "$p" ] && [ "$p" != "$1" ]; then echo "$p"; return; fi
    sleep 0.01
  done
}
first=$(worker_after none)
sleep 0.05  # a-crashes.off's worker is importing or building
kill -SEGV "$first" 2>/dev/null
second=$(worker_after "$first")
kill -STOP "$second" 2>/dev/null
wait "$batch"; isolate_exit=$?
check "the batch with a crashing, a hanging and a hungry input exits 1" test "$isolate_exit" -eq 1
check "its good inputs are converted" test -s "$work/isolate-out/d-good.tom" -a -s "$work/isolate-out/e-good.tom"
check "the crashed input is named with its signal" grep -q "a-crashes.off: the conversion crashed (signal 11" "$work/isolate.err"
check "the hanging input is named with its time limit" grep -q "b-hangs.off: took longer than --timeout 8 s" "$work/isolate.err"
check "the hungry input is named with its memory limit" grep -Eq "c-hungry.off: (needs more memory than this process may take .--max-memory 400 MB.|the conversion crashed .* memory limit)" "$work/isolate.err"
check "no failed input left a .tom or a temporary" test -z "$(find "$work/isolate-out" -mindepth 1 -name '*crashes*' -o -name '*hangs*' -o -name '*hungry*')"
check "the batch's message counts the three" grep -q "2 of 5 inputs converted, 3 failed" "$work/isolate.err"
[ "$fail" -eq 0 ] || cat "$work/isolate.err"
fi

check "usage error without -o exits 2" expect_exit 2 "$tools/tombuild" "$work/in"
check "unknown option exits 2" expect_exit 2 "$tools/tombuild" "$work/in" -o "$work/o" --no-such-option
check "bad predicate exits 2" expect_exit 2 "$tools/tombuild" "$work/in" -o "$work/o" --predicate nonsense
check "--help exits 0" expect_exit 0 "$tools/tombuild" --help
check "--help documents the exit codes" grep -q "Exit codes" "$work/stdout"
check "--version exits 0" expect_exit 0 "$tools/tombuild" --version
check "the version a .tom records names the output revision" bash -c "'$tools/tombuild' --version | grep -q 'output revision [0-9]' && '$tools/tombuild' -q '$data/meshes/cross.off' -o '$work/rev' && grep -a -q 'output revision' '$work/rev/cross.tom'"

check "a batch with bad inputs exits 1" expect_exit 1 "$tools/tombuild" "$work/in" -o "$work/o1" -j 1
check "the bad glTF is reported with its reason" grep -q "IndexOutOfRange.gltf.*out of range" "$work/stderr"
check "the file without triangles is reported" grep -q "testpoints.obj" "$work/stderr"
check "the good inputs were still converted" test -s "$work/o1/fandisk.tom" -a -s "$work/o1/cow.tom" -a -s "$work/o1/sub/spider.tom"
check "no output for the failed inputs" test ! -e "$work/o1/sub/IndexOutOfRange.tom" -a ! -e "$work/o1/testpoints.tom"
check "no temporary files left" test -z "$(find "$work/o1" -name '*.tmp*')"
check "summary line counts" grep -q "3 of 5 inputs converted, 2 failed" "$work/stderr"

check "-j 2 converts the same batch" expect_exit 1 "$tools/tombuild" "$work/in" -o "$work/o2" -j 2
for f in fandisk.tom cow.tom sub/spider.tom; do
  check "$f is byte-identical with -j 1 and -j 2" cmp -s "$work/o1/$f" "$work/o2/$f"
done
check "a good single input exits 0" expect_exit 0 "$tools/tombuild" "$data/meshes/fandisk.off" -o "$work/o3" --strategy heap --predicate memoryless
check "a missing input exits 1" expect_exit 1 "$tools/tombuild" "$work/nothing.off" -o "$work/o4"

check "tominfo reads a file" expect_exit 0 "$tools/tominfo" "$work/o1/fandisk.tom"
check "tominfo shows the counts" grep -q "6475" "$work/stdout"
check "tominfo --json" expect_exit 0 "$tools/tominfo" "$work/o1/fandisk.tom" --json
check "tominfo --json is JSON with the mesh" python3 -c "import json,sys; d=json.load(open('$work/stdout')); assert d['meshes'][0]['vertices']==6475, d"
check "tominfo --json shows the coarse corners (V / 64)" python3 -c "import json,sys; d=json.load(open('$work/stdout')); c=d['meshes'][0]['coarse_corners']; assert c['resolution']==6475//64 and c['triangles']>0, c"
head -c 500 "$work/o1/fandisk.tom" > "$work/truncated.tom"
check "tominfo on a truncated file exits 1" expect_exit 1 "$tools/tominfo" "$work/truncated.tom"
check "with a message naming the file and rule" grep -q "truncated.tom: byte 16, file_bytes: file is truncated.*rule 5" "$work/stderr"

check "tomextract 10% to OBJ" expect_exit 0 "$tools/tomextract" "$work/o1/fandisk.tom" --fraction 0.1 -o "$work/f10.obj"
check "the OBJ has 10% of the triangles" test "$(grep -c '^f ' "$work/f10.obj")" -ge 1290 -a "$(grep -c '^f ' "$work/f10.obj")" -le 1300
check "tomextract by triangle count to PLY" expect_exit 0 "$tools/tomextract" "$work/o1/cow.tom" --triangles 500 -o "$work/c.ply"
check "the PLY header declares the faces" grep -a -q "element face 50[0-9]" "$work/c.ply"
check "the extracted PLY converts back" expect_exit 0 "$tools/tombuild" "$work/c.ply" -o "$work/o5"
# the usable floor: spider's coarsest levels go far past 1% mean error; tombuild stores where
check "tombuild -v names each mesh's usable floor" bash -c "'$tools/tombuild' -v '$work/in/sub/spider.obj' -o '$work/floor' | grep -q 'usable floor [0-9]* vertices / [0-9]* triangles'"
# texture coordinates weigh in the build only when a texture samples them; -v says when not
check "tombuild -v: the textured spider's coordinates weigh" bash -c "! '$tools/tombuild' -v '$work/in/sub/spider.obj' -o '$work/uvw' | grep -q 'not weighed'"
check "without its materials they are carried, not weighed" bash -c "sed '/^mtllib/d; /^usemtl/d' '$work/in/sub/spider.obj' > '$work/bare-spider.obj' && '$tools/tombuild' -v '$work/bare-spider.obj' -o '$work/uvw' | grep -q 'texture coordinates carried, not weighed: no texture samples them' && '$tools/tominfo' --json '$work/uvw/bare-spider.tom' | python3 -c \"import json,sys; assert 'texcoord0' in json.dumps(json.load(sys.stdin))\""
check "tominfo --json shows it, above the chain's floor" bash -c "'$tools/tominfo' --json '$work/floor/spider.tom' > '$work/floor.json' && python3 -c \"import json; m=json.load(open('$work/floor.json'))['meshes'][0]; f=m['usable_floor']; assert abs(f['mean_bound_percent'] - 1) < 1e-6 and m['min_triangles'] < f['triangles'] < m['triangles'] // 2, m\""
check "tomextract --fraction 0 stops at the usable floor" bash -c "'$tools/tomextract' '$work/floor/spider.tom' --fraction 0 -o '$work/floor0.obj' && python3 -c \"import json; f=json.load(open('$work/floor.json'))['meshes'][0]['usable_floor']; assert open('$work/floor0.obj').read().count('\\nf ')==f['triangles']\""
check "and --below-floor goes to the chain's last level" bash -c "'$tools/tomextract' '$work/floor/spider.tom' --fraction 0 --below-floor -o '$work/floor-below.obj' && python3 -c \"import json; m=json.load(open('$work/floor.json'))['meshes'][0]; assert open('$work/floor-below.obj').read().count('\\nf ')==m['min_triangles']\""
check "--floor-error 0 stores none" bash -c "'$tools/tombuild' -q '$work/in/sub/spider.obj' -o '$work/nofloor' --floor-error 0 && '$tools/tominfo' --json '$work/nofloor/spider.tom' | python3 -c \"import json,sys; assert json.load(sys.stdin)['meshes'][0]['usable_floor'] is None\""
check "tomextract without a resolution exits 2" expect_exit 2 "$tools/tomextract" "$work/o1/cow.tom" -o "$work/x.obj"
check "tomextract to an unknown type exits 1" expect_exit 1 "$tools/tomextract" "$work/o1/cow.tom" --fraction 0.5 -o "$work/x.xyz"

# glTF out: one level, or levels through MSFT_lod; Khronos' validator; back through our importer
check "tomextract a level to .glb" expect_exit 0 "$tools/tomextract" "$work/o1/cow.tom" --fraction 0.2 -o "$work/cow20.glb"
check "tomextract --lods to .glb" expect_exit 0 "$tools/tomextract" "$work/o1/fandisk.tom" --lods 100,50,25,10 -o "$work/fandisk-lods.glb"
# --refit: the level written on its own, its vertices moved to fit the surface they replaced:
# closer to the source by tomerr's two-sided mean, to OBJ and to a compressed .glb alike; in a
# chain each level gets positions of its own
check "tomextract --refit to OBJ" expect_exit 0 "$tools/tomextract" "$work/o1/cow.tom" --fraction 0.25 --refit -o "$work/cow25-refit.obj"
check "tomextract --refit to a compressed .glb" expect_exit 0 "$tools/tomextract" "$work/o1/cow.tom" --fraction 0.25 --refit -c -o "$work/cow25-refit.glb"
"$tools/tomextract" "$work/o1/cow.tom" --fraction 0.25 -o "$work/cow25.obj" > /dev/null
check "a re-fitted level is closer to the source than the plain one, and has its triangles" /usr/bin/python3 -c "
import json, subprocess
def err(f): return json.loads(subprocess.run(['$tools/tomerr', '$data/meshes/cow.off', f, '--json'], capture_output=True, text=True, check=True).stdout)
plain, refit, glb = err('$work/cow25.obj'), err('$work/cow25-refit.obj'), err('$work/cow25-refit.glb')
assert refit['simplified_triangles'] == plain['simplified_triangles'] == glb['simplified_triangles'], (plain, refit, glb)
assert refit['mean'] < 0.9 * plain['mean'] and glb['mean'] < 0.9 * plain['mean'], (plain['mean'], refit['mean'], glb['mean'])
"
check "tomextract --refit on a chain of levels" expect_exit 0 "$tools/tomextract" "$work/o1/cow.tom" --lods 25,10 --refit -c -o "$work/cow-chain-refit.glb"
check "each level of a re-fitted chain has positions of its own; its finest is the level re-fitted alone" /usr/bin/python3 -c "
import json, struct, subprocess
b = open('$work/cow-chain-refit.glb', 'rb').read()
d = json.loads(b[20:20 + struct.unpack('<I', b[12:16])[0]])
positions = [m['primitives'][0]['attributes']['POSITION'] for m in d['meshes']]
assert len(positions) == 2 and positions[0] != positions[1], positions
def mean(f): return json.loads(subprocess.run(['$tools/tomerr', '$data/meshes/cow.off', f, '--json'], capture_output=True, text=True, check=True).stdout)['mean']
assert mean('$work/cow-chain-refit.glb') == mean('$work/cow25-refit.glb')
"
"$tools/tombuild" "$data/assimp/glTF2/2CylinderEngine-glTF-Binary/2CylinderEngine.glb" -o "$work/engine" -q
check "a 34-primitive glTF to .glb" expect_exit 0 "$tools/tomextract" "$work/engine/2CylinderEngine.tom" --fraction 0.25 -o "$work/engine25.glb"
# parts: 29 meshes, four of several primitives; every level of them keeps every part's primitive
check "tominfo lists the parts with their materials" bash -c "'$tools/tominfo' '$work/engine/2CylinderEngine.tom' | grep -c '^    part ' | grep -qx 9"
check "multi-part meshes through MSFT_lod" expect_exit 0 "$tools/tomextract" "$work/engine/2CylinderEngine.tom" --lods 100,25,5 -o "$work/engine-lods.glb"
check "each level of a multi-part mesh has a primitive per part, each with its material" /usr/bin/python3 -c "
import json, struct
b = open('$work/engine-lods.glb', 'rb').read()
n = struct.unpack('<I', b[12:16])[0]; d = json.loads(b[20:20 + n])
counts = {}
for m in d['meshes']:
    name = m['name'].rsplit(' level ', 1)[0]
    counts.setdefault(name, []).append([p['material'] for p in m['primitives']])
multi = {k: v for k, v in counts.items() if len(v[0]) > 1}
assert len(multi) == 4, multi.keys()
for k, levels in multi.items():
    assert len(levels) == 3 and all(l == levels[0] for l in levels), (k, levels)
"
check "--triangles on a scene with floored meshes never exceeds the count" bash -c "'$tools/tomextract' '$work/engine/2CylinderEngine.tom' --triangles 20000 -o '$work/engine-20k.obj' | grep -q ' 20000 triangles\\| 1999[0-9] triangles'"
check "and below every floor writes the floors with a warning" bash -c "'$tools/tomextract' '$work/engine/2CylinderEngine.tom' --triangles 5000 -o '$work/engine-5k.obj' 2>'$work/5k.err' && grep -q 'more than the 5000 asked for' '$work/5k.err'"
check "--scene-budget shares a scene's triangles, one level per budget" expect_exit 0 "$tools/tomextract" "$work/engine/2CylinderEngine.tom" --scene-budget 40000,30000 -o "$work/engine-budget.glb"
check "drawing at most each budget, certified near the optimum" /usr/bin/python3 -c "
import re
lines = [l for l in open('$work/stdout') if 'scene budget' in l]
assert len(lines) == 2, lines
for l in lines:
    budget, drawn, gap = (float(x) for x in re.search(r'scene budget (\\d+) triangles: (\\d+) drawn, .* certified within ([0-9.]+)%', l).groups())
    assert drawn <= budget and drawn > 0.95 * budget and gap < 1, l
"
check "--scene-budget below the floors warns and writes them" bash -c "'$tools/tomextract' '$work/engine/2CylinderEngine.tom' --scene-budget 100 -o '$work/engine-floor.obj' 2>'$work/floor.err' && grep -q 'more than the budget of 100; each is at its floor' '$work/floor.err'"
check "OBJ out: a usemtl group per part and the .mtl beside it" expect_exit 0 "$tools/tomextract" "$work/engine/2CylinderEngine.tom" --fraction 0.25 -o "$work/engine25.obj"
check "with every material the groups use" bash -c "test \$(grep -c '^usemtl ' '$work/engine25.obj') -eq 34 && grep -q '^mtllib engine25.mtl' '$work/engine25.obj' && test \$(grep -c '^newmtl ' '$work/engine25.mtl') -eq 34"
check "the OBJ converts back with its parts" expect_exit 0 "$tools/tombuild" "$work/engine25.obj" -o "$work/obj-back" -q
check "the OBJ's mesh has the 34 parts" bash -c "'$tools/tominfo' '$work/obj-back/engine25.tom' | grep -q 'mesh 0: 34 parts'"
# a scene: materials with a texture file, node transforms, instances
"$tools/tombuild" "$data/assimp/glTF2/BoxTextured-glTF/BoxTextured.gltf" "$data/assimp/glTF2/textureTransform/TextureTransformTest.gltf" -o "$work/scenes" -q
check "tominfo --scene lists materials, textures and instances" expect_exit 0 "$tools/tominfo" "$work/scenes/BoxTextured.tom" --scene
check "with the texture URI" grep -q "baseColor texture (TEXCOORD_0): CesiumLogoFlat.png" "$work/stdout"
check "tomextract a scene with --texture-dir" expect_exit 0 "$tools/tomextract" "$work/scenes/BoxTextured.tom" --fraction 0.5 -o "$work/box/box.glb" --texture-dir "$data/assimp/glTF2/BoxTextured-glTF"
check "the box's node keeps its rotation and its material its texture" /usr/bin/python3 -c "
import json, struct, os
b = open('$work/box/box.glb', 'rb').read()
n = struct.unpack('<I', b[12:16])[0]; d = json.loads(b[20:20 + n])
assert d['nodes'][0]['matrix'][5] == 0.0 and d['nodes'][0]['matrix'][6] == -1.0, d['nodes']
assert d['materials'][0]['name'] == 'Texture' and d['materials'][0]['pbrMetallicRoughness']['baseColorTexture']['index'] == 0
assert os.path.isfile(os.path.join('$work/box', d['images'][0]['uri'])), d['images']
"
# nothing lost without a word: an embedded image round-trips byte for byte, a file image embeds
# on request, and what the .tom does not keep is named on stderr and in the manifest
check "a GLB with its image in the binary chunk, a skinned and a clear-coat glTF convert" expect_exit 0 "$tools/tombuild" "$data/assimp/glTF2/BoxTextured-glTF-Binary/BoxTextured.glb" "$data/assimp/glTF2/simple_skin/simple_skin.gltf" "$data/assimp/glTF2/ClearCoat-glTF/ClearCoatTest.gltf" -o "$work/kept" -q
check "with no warning: nothing is dropped" bash -c "! grep -q warning '$work/stderr'"
check "the manifest says so" /usr/bin/python3 -c "
import json
lines = [json.loads(l) for l in open('$work/kept/manifest.jsonl')]
by = {l['input'].split('/')[-1]: l['dropped'] for l in lines if 'input' in l}
assert by == {'BoxTextured.glb': [], 'simple_skin.gltf': [], 'ClearCoatTest.gltf': []}, by
"
sg="$data/assimp/glTF2/BoxTextured-glTF-pbrSpecularGlossiness/BoxTextured.gltf"
check "a specular-glossiness glTF converts" expect_exit 0 "$tools/tombuild" "$sg" -o "$work/dropped" -q
check "one warning names the file and what it does not carry" bash -c "test \$(grep -c warning '$work/stderr') -eq 1 && grep -q 'warning: .*pbrSpecularGlossiness/BoxTextured.gltf: not carried into the .tom: extension KHR_materials_pbrSpecularGlossiness' '$work/stderr'"
check "the manifest lists it" bash -c "grep -q '\"dropped\":\[\"extension KHR_materials_pbrSpecularGlossiness (its specular and glossiness; the diffuse is kept as the base colour)\"\]' '$work/dropped/manifest.jsonl'"
check "a rerun says up to date and keeps the list" bash -c "'$tools/tombuild' '$sg' -o '$work/dropped' -q 2>'$work/rerun.err' && ! grep -q warning '$work/rerun.err' && grep -q '\"status\":\"up to date\",\"dropped\":\[\"extension KHR_materials_pbrSpecularGlossiness (its specular and glossiness; the diffuse is kept as the base colour)\"\]' '$work/dropped/manifest.jsonl'"
# assimp's glTF of the Collada and FBX samples (scripts/fetch-samples.sh) as a user batch-converts
# them: every one converts (a model's 3-component texture coordinates read as u and v), nothing
# is lost without a word, and extensions only declared are not named
conv="$data/assimp/converted"
check "assimp's conversions of the Collada and FBX samples all convert" expect_exit 0 "$tools/tombuild" "$conv" -o "$work/conv" -q
check "without an error" bash -c "! grep -q '^error' '$work/stderr'"
check "each converts (the Duck with its 4,212 triangles), naming only extensions some object uses" /usr/bin/python3 -c "
import json, glob, struct
lines = [json.loads(l) for l in open('$work/conv/manifest.jsonl') if 'input' in l]
assert len(lines) == len(glob.glob('$conv/*/*.glb')), len(lines)
converted = {l['input']: l for l in lines if l['status'] == 'converted'}
assert len(converted) == len(lines), len(converted)
for path, l in converted.items():
    b = open(path, 'rb').read()
    doc = json.loads(b[20:20 + struct.unpack_from('<I', b, 12)[0]])
    used = set(k for m in doc.get('meshes', []) for p in m['primitives'] for k in p.get('extensions', {}))
    used |= set(k for m in doc.get('materials', []) for k in m.get('extensions', {}))
    named = {d.split(' ')[1] for d in l['dropped'] if d.startswith('extension ')}
    assert named <= used, (path, named, used)
    assert 'KHR_materials_volume' not in named, path
duck = [l for p, l in converted.items() if p.endswith('duck-dae.glb')][0]
assert duck['triangles'] == 4212, duck
"
# the Duck's texture seams keep their shape (their edge planes): at half its triangles its texture
# coordinates deviate by at most 1.45e-4 (1.8e-4 without the planes, gltfpack -sv 0.96e-4)
check "the Duck at 50%: its texture seams hold" /usr/bin/python3 -c "
import json, subprocess
def run(*args): return subprocess.run(args, capture_output=True, text=True, check=True).stdout
run('$tools/tomextract', '$work/conv/Collada/duck-dae.tom', '--fraction', '0.5', '-o', '$work/duck50.glb')
d = json.loads(run('$tools/tomerr', '$conv/Collada/duck-dae.glb', '$work/duck50.glb', '--json'))
assert d['simplified_triangles'] == 2106, d['simplified_triangles']
assert d['attributes']['uv_mean'] <= 1.45e-4, d['attributes']
"
# a scene budget shared by area: the FBX spider is 19 meshes (legs, teeth, eyes); its share at
# 1,010 triangles has well under the mean error of every mesh at the same fraction
check "--scene-budget on a scene of 19 meshes: the budget goes where the surface is" /usr/bin/python3 -c "
import json, subprocess
tom, src = '$work/conv/FBX/spider-fbx.tom', '$conv/FBX/spider-fbx.glb'
def run(*args): return subprocess.run(args, capture_output=True, text=True, check=True).stdout
def error(path): return json.loads(run('$tools/tomerr', src, path, '--json'))
run('$tools/tomextract', tom, '--scene-budget', '1010', '-o', '$work/spider-budget.glb')
run('$tools/tomextract', tom, '--triangles', '1010', '-o', '$work/spider-fraction.glb')
shared, proportional = error('$work/spider-budget.glb'), error('$work/spider-fraction.glb')
assert shared['simplified_triangles'] <= 1010, shared['simplified_triangles']
assert shared['forward']['mean_abs'] < 0.5 * proportional['forward']['mean_abs'], (shared['forward'], proportional['forward'])
"
# the benchmark's posing (scripts/pose.py, scripts/real-assets.sh): the skinned character's
# animation moves it from its bind pose (the first key's pose); its full-detail level is posed
# exactly as its source at every pose, a coarser one departs from it further as it moves, and a
# model that does not move is refused with status 3
check "a skinned level posed by its source's animation: exact at full detail, apart at 50%" /usr/bin/python3 -c "
import json, subprocess
src, tom = '$conv/FBX/animation_with_skeleton-fbx.glb', '$work/conv/FBX/animation_with_skeleton-fbx.tom'
def run(*args): return subprocess.run(args, capture_output=True, text=True, check=True).stdout
run('$tools/tomextract', tom, '--fraction', '1', '-o', '$work/skin100.glb')
run('$tools/tomextract', tom, '--fraction', '0.5', '-o', '$work/skin50.glb')
for prefix, level in (('source', src), ('full', '$work/skin100.glb'), ('half', '$work/skin50.glb')):
    run('/usr/bin/python3', '$src/scripts/pose.py', src, level, '$work/posed-' + prefix, '--poses', '4')
def error(a, b): return json.loads(run('$tools/tomerr', a, b, '--json'))
rest = error(src, '$work/posed-source-0.obj')  # the animation's first key is this model's bind pose
assert rest['hausdorff'] < 1e-3 and rest['attributes']['normal_mean_degrees'] < 1e-3 and rest['attributes']['uv_mean'] < 1e-5, (rest['hausdorff'], rest['attributes'])
moved = error('$work/posed-source-0.obj', '$work/posed-source-3.obj')
assert moved['hausdorff'] > 2, moved['hausdorff']  # % of the diagonal: the last pose is not the first
halves = []
for k in range(4):
    full, half = error('$work/posed-source-%d.obj' % k, '$work/posed-full-%d.obj' % k), error('$work/posed-source-%d.obj' % k, '$work/posed-half-%d.obj' % k)
    assert full['hausdorff'] < 1e-9 and full['attributes']['normal_mean_degrees'] < 1e-3, (k, full['hausdorff'], full['attributes'])
    assert half['simplified_triangles'] == 1056 and half['mean'] > 1e-3, (k, half['simplified_triangles'], half['mean'])
    halves.append(half['mean'])
assert max(halves) > 1.5 * halves[0], halves  # the first pose is the bind pose; moving, the level departs further
"
check "a model without an animation is not posed (status 3)" expect_exit 3 /usr/bin/python3 "$src/scripts/pose.py" "$conv/Collada/duck-dae.glb" "$conv/Collada/duck-dae.glb" "$work/duck-posed"
check "tomextract --lods 100 embeds the stored image" expect_exit 0 "$tools/tomextract" "$work/kept/BoxTextured.tom" --lods 100 -o "$work/kept/box.glb"
check "the image bytes are the source's" /usr/bin/python3 -c "
import json, struct
def images(path):
    b = open(path, 'rb').read()
    n = struct.unpack('<I', b[12:16])[0]; d = json.loads(b[20:20 + n]); binary = b[28 + n:]
    out = []
    for i in d['images']:
        v = d['bufferViews'][i['bufferView']]; o = v.get('byteOffset', 0)
        out.append((i['mimeType'], binary[o:o + v['byteLength']]))
    return out
assert images('$work/kept/box.glb') == images('$data/assimp/glTF2/BoxTextured-glTF-Binary/BoxTextured.glb')
"
check "--embed-images embeds a file image too" expect_exit 0 "$tools/tomextract" "$work/scenes/BoxTextured.tom" --lods 100 -o "$work/kept/box-embedded.glb" --texture-dir "$data/assimp/glTF2/BoxTextured-glTF" --embed-images
check "without --texture-dir the source's folder comes from the manifest" bash -c "cd '$work/box' && '$tools/tomextract' ../scenes/BoxTextured.tom --lods 100 -o from-manifest.glb --embed-images >/dev/null"
check "and the embedded image is the source's file, byte for byte" /usr/bin/python3 -c "
import json, struct
b = open('$work/box/from-manifest.glb', 'rb').read()
n = struct.unpack('<I', b[12:16])[0]; d = json.loads(b[20:20 + n]); binary = b[28 + n:]
v = d['bufferViews'][d['images'][0]['bufferView']]; o = v.get('byteOffset', 0)
assert binary[o:o + v['byteLength']] == open('$data/assimp/glTF2/BoxTextured-glTF/CesiumLogoFlat.png', 'rb').read()
"
check "--embed-images needs a .glb" expect_exit 2 "$tools/tomextract" "$work/scenes/BoxTextured.tom" --fraction 1 -o "$work/kept/box.obj" --embed-images
# every glTF2 sample that converts, back to glTF: materials, mesh nodes and images kept, and the
# validator content (but for texcoord_crash.gltf, which the validator rejects as shipped)
"$tools/tombuild" "$data/assimp/glTF2" -o "$work/gltf2" -q --no-error-curve 2>/dev/null
for t in $(cd "$work/gltf2" && find . -name '*.tom'); do
  "$tools/tomextract" "$work/gltf2/$t" --lods 100 -o "$work/gltf2/${t%.tom}.glb" --texture-dir "$data/assimp/glTF2/$(dirname "$t")" >/dev/null || echo "FAILED: tomextract $t"
done
check "the glTF2 samples keep materials, mesh nodes and image bytes through the round trip" /usr/bin/python3 "$src/tests/cli/gltf_round_trip.py" "$work/gltf2"
mv "$work/gltf2/issue_3269/texcoord_crash.glb" "$work/texcoord_crash.glb"
# ClearCoatTest.gltf has one error as shipped (a clear-coat normal map on a primitive without
# tangents): the output keeps it, and no other (validated where it was written: its image URIs
# are relative to that folder)
clearcoat="$work/gltf2/ClearCoat-glTF/ClearCoatTest.glb"
check "and validate with no errors" node "$src/scripts/validate-gltf.mjs" $(find "$work/gltf2" -name '*.glb' ! -path "$clearcoat")
check "the clear-coat sample's only error is the source's own" bash -c "node '$src/scripts/validate-gltf.mjs' '$clearcoat' | grep -q '1 errors' && node '$src/scripts/validate-gltf.mjs' '$clearcoat' | grep -q 'MESH_PRIMITIVE_NO_TANGENT_SPACE: .*(/meshes/13/primitives/0/material)'" 
# the same samples compressed (-c): valid, and read back with every triangle
for t in $(cd "$work/gltf2" && find . -name '*.tom'); do
  mkdir -p "$work/gltf2c/$(dirname "$t")"
  "$tools/tomextract" "$work/gltf2/$t" --lods 100 -c -o "$work/gltf2c/${t%.tom}.glb" --texture-dir "$data/assimp/glTF2/$(dirname "$t")" >/dev/null || echo "FAILED: tomextract -c $t"
done
rm -f "$work/gltf2c/issue_3269/texcoord_crash.glb" "$work/gltf2c/ClearCoat-glTF/ClearCoatTest.glb"
check "-c output of the glTF2 samples validates with no errors" node "$src/scripts/validate-gltf.mjs" $(find "$work/gltf2c" -name '*.glb')
# (--no-weld: quantization makes a few vertices identical, whose zero-area triangles a weld drops)
"$tools/tombuild" "$work/gltf2c" -o "$work/gltf2c-back" -q --no-error-curve --no-weld 2>/dev/null
check "and tombuild reads every one back with the triangles it was written with" /usr/bin/python3 -c "
import json, os
def triangles(manifest, root):
    out = {}
    for line in open(manifest):
        r = json.loads(line)
        if r.get('status') == 'converted': out[os.path.splitext(os.path.relpath(r['output'], root))[0]] = r['triangles']
    return out
before = triangles('$work/gltf2/manifest.jsonl', '$work/gltf2')
after = triangles('$work/gltf2c-back/manifest.jsonl', '$work/gltf2c-back')
for skipped in ('issue_3269/texcoord_crash', 'ClearCoat-glTF/ClearCoatTest'): before.pop(skipped, None)
assert before == after and len(after) >= 20, (before, after)
"
check "tomextract the 12-instance texture-transform scene with its levels" expect_exit 0 "$tools/tomextract" "$work/scenes/TextureTransformTest.tom" --lods 100,50 -o "$work/tt.glb" --texture-dir "$data/assimp/glTF2/textureTransform"
check "the .glb files validate with no errors" node "$src/scripts/validate-gltf.mjs" "$work/cow20.glb" "$work/cow25-refit.glb" "$work/cow-chain-refit.glb" "$work/fandisk-lods.glb" "$work/engine25.glb" "$work/engine-lods.glb" "$work/box/box.glb" "$work/tt.glb" "$work/kept/box.glb" "$work/kept/box-embedded.glb"
check "MSFT_lod lists the three coarser levels, coarser in order" /usr/bin/python3 -c "
import json, struct
b = open('$work/fandisk-lods.glb', 'rb').read()
n = struct.unpack('<I', b[12:16])[0]; d = json.loads(b[20:20 + n])
assert d['extensionsUsed'] == ['MSFT_lod'], d.get('extensionsUsed')
assert d['nodes'][0]['extensions']['MSFT_lod']['ids'] == [1, 2, 3]
counts = [d['accessors'][m['primitives'][0]['indices']]['count'] // 3 for m in d['meshes']]
assert counts[0] == 12946 and counts[0] > counts[1] > counts[2] > counts[3], counts
assert abs(counts[1] - 6473) <= 3 and abs(counts[3] - 1295) <= 3, counts
"
check "the .glb converts back with every primitive" expect_exit 0 "$tools/tombuild" "$work/engine25.glb" -o "$work/back"
check "29 meshes of 34 parts come back" bash -c "'$tools/tominfo' '$work/back/engine25.tom' --json | /usr/bin/python3 -c 'import json,sys; d=json.load(sys.stdin); assert d[\"mesh_count\"] == 29 and sum(max(1, len(m.get(\"parts\", []))) for m in d[\"meshes\"]) == 34, d[\"mesh_count\"]'"
check "--lods needs a .glb" expect_exit 2 "$tools/tomextract" "$work/o1/cow.tom" --lods 100,50 -o "$work/x.obj"

# reports: the table, one JSON per input valid against the schema, the batch summary, plots
check "tombuild --report --report-json" expect_exit 0 "$tools/tombuild" "$data/meshes/fandisk.off" "$data/meshes/cow.off" -o "$work/r" --report --report-json "$work/r/reports" --levels 50,10,2
check "the report table has the levels" grep -q "^   10.0%" "$work/stdout"
check "the report table states the conventions" grep -q "samples/face of the larger mesh" "$work/stdout"
# cross.off, keeping its topology, stops simplifying at a tetrahedron: its last levels repeat the
# 5% level's mesh, and say so
check "tombuild --report on a mesh with a floor" expect_exit 0 "$tools/tombuild" "$data/meshes/cross.off" -o "$work/floor" --keep-topology --report --report-json "$work/floor"
check "the repeated levels are named once" grep -q "^  2.0%, 1.0%, 0.5%: the 5.0% level's mesh again (4 vertices, 4 triangles" "$work/stdout"
check "with the figures of the level they repeat" /usr/bin/python3 -c "
import json; levels = json.load(open('$work/floor/cross.json'))['meshes'][0]['levels']
assert [l['vertices'] for l in levels[3:]] == [4, 4, 4, 4], [l['vertices'] for l in levels]
assert all(l['error'] == levels[3]['error'] and l['attributes'] == levels[3]['attributes'] for l in levels[4:])
assert levels[2]['vertices'] > 4
"
check "tombuild --report with --levels in any order" expect_exit 0 "$tools/tombuild" "$data/meshes/cross.off" -o "$work/floor2" --keep-topology --report --levels 10,50,2,25,1
check "names the repeats of each level, and only those" grep -qx "  1.0%: the 2.0% level's mesh again (4 vertices, 4 triangles)" "$work/stdout"
check "one JSON per input" test -s "$work/r/reports/fandisk.json" -a -s "$work/r/reports/cow.json"
check "the JSON reports follow libtom/metrics/report.schema.json" /usr/bin/python3 -c "
import json, jsonschema, sys
schema = json.load(open('$src/libtom/metrics/report.schema.json'))
for f in sys.argv[1:]:
    doc = json.load(open(f))
    jsonschema.validate(doc, schema)
    assert [l['fraction'] for l in doc['meshes'][0]['levels']] == [0.5, 0.1, 0.02], doc['meshes'][0]['levels']
" "$work/r/reports/fandisk.json" "$work/r/reports/cow.json"
check "summary.csv has a header and a row per mesh" test "$(wc -l < "$work/r/reports/summary.csv")" -eq 3
check "summary.csv columns" grep -q "^file,mesh,vertices,triangles,build_seconds,report_seconds,tom_percent,k_mean,k_max,triangles_50,hausdorff_50,mean_50" "$work/r/reports/summary.csv"
check "plots are drawn" "$src/scripts/plot-report.py" "$work/r/reports/fandisk.json" "$work/r/reports/cow.json" -o "$work/plots"
for f in fandisk-error.svg fandisk-chains.svg cow-error.svg cow-chains.svg; do
  check "plot $f is an SVG with content" grep -q "<svg" "$work/plots/$f"
done
check "the stored error curve is shown by tominfo --curve" expect_exit 0 "$tools/tominfo" "$work/r/fandisk.tom" --curve
check "tominfo prints the curve and k" grep -q "error curve (% of the diagonal" "$work/stdout"
check "--no-error-curve stores none" expect_exit 0 "$tools/tombuild" "$data/meshes/fandisk.off" -o "$work/nc" --no-error-curve
check "tominfo says so" bash -c "'$tools/tominfo' '$work/nc/fandisk.tom' --curve | grep -q 'no error curve stored'"
check "--no-error-curve with a report" expect_exit 0 "$tools/tombuild" "$data/meshes/fandisk.off" -o "$work/ncr" --report-json "$work/ncr" --levels 50,10,2 --no-error-curve
check "reports the same levels, no curve measured, still valid against the schema" /usr/bin/python3 -c "
import json, jsonschema
schema = json.load(open('$src/libtom/metrics/report.schema.json'))
plain = json.load(open('$work/ncr/fandisk.json')); full = json.load(open('$work/r/reports/fandisk.json'))
jsonschema.validate(plain, schema)
m, f = plain['meshes'][0], full['meshes'][0]
assert m['error_curve'] is None and f['error_curve']['points'], (m['error_curve'], f['error_curve'])
assert [l['error'] for l in m['levels']] == [l['error'] for l in f['levels']]
assert m['fit'] == f['fit']
"
check "and stores none" bash -c "'$tools/tominfo' '$work/ncr/fandisk.tom' --curve | grep -q 'no error curve stored'"
check "plots a report without a curve" "$src/scripts/plot-report.py" "$work/ncr/fandisk.json" -o "$work/ncplots"
check "its error plot is an SVG" grep -q "<svg" "$work/ncplots/fandisk-error.svg"

# tomerr: the same yardstick for any two files
check "tomerr of a mesh and itself" expect_exit 0 "$tools/tomerr" "$data/meshes/fandisk.off" "$data/meshes/fandisk.off" --json
check "is 0, normals included" /usr/bin/python3 -c "import json; d=json.load(open('$work/stdout')); assert d['hausdorff'] < 1e-6 and d['forward']['samples'] >= 129000 and d['attributes']['normal_mean_degrees'] < 1e-3 and d['attributes']['uv_mean'] is None, d"
check "tomerr against a .tom level" expect_exit 0 "$tools/tomerr" "$data/meshes/fandisk.off" "$work/r/fandisk.tom" --fraction 0.1 --json
check "matches the report's figure for that level" /usr/bin/python3 -c "
import json
d = json.load(open('$work/stdout')); r = json.load(open('$work/r/reports/fandisk.json'))
level = [l for l in r['meshes'][0]['levels'] if l['fraction'] == 0.1][0]
assert d['simplified_triangles'] == level['triangles'], (d['simplified_triangles'], level['triangles'])
assert abs(d['hausdorff'] - level['error']['hausdorff']) < 1e-9 and abs(d['mean'] - level['error']['mean']) < 1e-9, (d, level['error'])
"
# levels chosen by error: what tomerr measures at the level is within the bound asked for
for bound in 0.2 1 3; do
  check "tomextract --max-error $bound% of fandisk" expect_exit 0 "$tools/tomextract" "$work/r/fandisk.tom" --max-error "$bound%" -o "$work/fe$bound.obj"
  check "whose Hausdorff distance, measured by tomerr, is at most $bound%" /usr/bin/python3 -c "
import json, subprocess
d = json.loads(subprocess.run(['$tools/tomerr', '$data/meshes/fandisk.off', '$work/fe$bound.obj', '--json'], check=True, capture_output=True, text=True).stdout)
assert d['hausdorff'] <= $bound and d['simplified_triangles'] < d['original_triangles'], d
"
done
check "--lods-error writes one level per bound, finer first" expect_exit 0 "$tools/tomextract" "$work/r/fandisk.tom" --lods-error 0.2%,1%,3% -o "$work/fe-lods.glb"
check "with strictly fewer triangles each" /usr/bin/python3 -c "
import json, struct
b = open('$work/fe-lods.glb', 'rb').read()
n = struct.unpack('<I', b[12:16])[0]; d = json.loads(b[20:20 + n])
counts = [d['accessors'][m['primitives'][0]['indices']]['count'] // 3 for m in d['meshes']]
assert len(counts) == 3 and counts[0] > counts[1] > counts[2], counts
"
check "--max-error-px takes the view" expect_exit 0 "$tools/tomextract" "$work/r/fandisk.tom" --max-error-px 2 --distance 3 --fov 60 --height 1080 -o "$work/fe-px.obj"
check "--max-error-px without the view is a usage error" expect_exit 2 "$tools/tomextract" "$work/r/fandisk.tom" --max-error-px 2 -o "$work/fe-px.obj"
check "--max-error of a file without error curves names the reason" bash -c "! '$tools/tomextract' '$work/nc/fandisk.tom' --max-error 1% -o '$work/nc.obj' 2>'$work/nc.err' && grep -q 'has no stored error curve' '$work/nc.err'"
check "tomerr text output" expect_exit 0 "$tools/tomerr" "$data/meshes/fandisk.off" "$work/f10.obj"
check "names both directions and Hausdorff" grep -q "Hausdorff distance" "$work/stdout"
check "tomerr with a missing file exits 1" expect_exit 1 "$tools/tomerr" "$data/meshes/fandisk.off" "$work/missing.obj"
check "tomerr without arguments exits 2" expect_exit 2 "$tools/tomerr"

# tcrmodel: Pasman & Jansen's model, the paper's example against its switching distances, a
# mesh's own k from its stored error curve, the CSV and its plot
check "tcrmodel --paper-example --json" expect_exit 0 "$tools/tcrmodel" --paper-example --json
check "its switching distances are the paper's within 25% (polygons, full resolution)" /usr/bin/python3 -c "
import json
d = json.load(open('$work/stdout'))
for key in ('polygons_below_m', 'simple_imposters_above_m', 'full_resolution_below_m'):
    assert isinstance(d[key], float) and d[key] > 0, (key, d[key])
assert abs(d['paper']['ratio_polygons_below'] - 1) <= 0.25 and abs(d['paper']['ratio_full_resolution_below'] - 1) <= 0.25, d['paper']
assert d['full_resolution_below_m'] < d['polygons_below_m'] < d['simple_imposters_above_m']
row = [r for r in d['distances'] if r['distance_m'] == 30][0]
m = {x['method']: x for x in row['methods']}
assert m['meshed_imposter']['feasible'] and not m['simple_imposter']['feasible'], row
assert m['polygons']['geometry_bytes'] == 25 * m['polygons']['polygons'] / 8
"
"$tools/tombuild" "$data/meshes/bunny00.off" -o "$work/model" -q
check "tcrmodel --tom reads k and the triangles from the stored curve" expect_exit 0 "$tools/tcrmodel" --tom "$work/model/bunny00.tom" --scale 10 --csv "$work/model.csv"
bunny_triangles=$("$tools/tominfo" --json "$work/model/bunny00.tom" | /usr/bin/python3 -c "import json,sys; print(json.load(sys.stdin)['meshes'][0]['triangles'])")
check "and takes the mesh's triangles as the full model" grep -q "at most $bunny_triangles polygons" "$work/stdout"
check "plot-model.py draws the CSV" bash -c "/usr/bin/python3 '$src/scripts/plot-model.py' '$work/model.csv' -o '$work/model.png' >/dev/null && test -s '$work/model.png'"
"$tools/tombuild" "$data/meshes/fandisk.off" -o "$work/model-nc" -q --no-error-curve
check "tcrmodel --tom without a stored curve exits 1" expect_exit 1 "$tools/tcrmodel" --tom "$work/model-nc/fandisk.tom"
check "and says why" grep -q "no mesh has a stored error curve" "$work/stderr"

# streamed files (tombuild --stream): every tool reads them; tominfo lists the chunks;
# tomextract --bytes writes what a prefix decodes to, the level of the ordinary file there
"$tools/tombuild" "$data/meshes/bunny00.off" "$data/assimp/OBJ/spider.obj" -o "$work/streamed" -q --stream
"$tools/tombuild" "$data/meshes/bunny00.off" -o "$work/plain" -q
check "tominfo --json lists a streamed file's chunks in file order" expect_exit 0 "$tools/tominfo" --json "$work/streamed/bunny00.tom"
check "their end bytes rise to the file's size, their vertices and triangles to the mesh's" /usr/bin/python3 -c "
import json, os
d = json.load(open('$work/stdout'))
c = d['stream']['chunks']
assert len(c) >= 10 and all(a['end_byte'] < b['end_byte'] and a['vertices'] < b['vertices'] and a['triangles'] < b['triangles'] for a, b in zip(c, c[1:])), c
assert c[-1]['end_byte'] == os.path.getsize('$work/streamed/bunny00.tom') == d['stream']['file_bytes']
assert c[-1]['vertices'] == d['meshes'][0]['vertices'] and c[-1]['triangles'] == d['meshes'][0]['triangles']
assert c[0]['end_byte'] < 0.05 * d['stream']['file_bytes'], c[0]
open('$work/chunk5', 'w').write('%d %d %d' % (c[5]['end_byte'], c[5]['vertices'], c[5]['triangles']))
"
read -r end5 vertices5 triangles5 < "$work/chunk5"
check "tomextract --bytes writes the mesh of the last whole chunk" expect_exit 0 "$tools/tomextract" "$work/streamed/bunny00.tom" --bytes $((end5 + 100)) -o "$work/prefix.obj"
check "which has that chunk's vertices and triangles" grep -q "$vertices5 vertices, $triangles5 triangles" "$work/stdout"
"$tools/tomextract" "$work/plain/bunny00.tom" --vertices "$vertices5" -o "$work/level.obj" > /dev/null
check "and the ordinary file's level there, the same surface within the quantization" /usr/bin/python3 -c "
import json, subprocess
e = json.loads(subprocess.run(['$tools/tomerr', '$work/level.obj', '$work/prefix.obj', '--json'], capture_output=True, check=True).stdout)
assert e['simplified_triangles'] == e['original_triangles'] == $triangles5, e
assert max(e['forward']['max'], e['backward']['max']) < 0.005, e  # % of the diagonal: a position moves at most a 14-bit step per axis (0.006), mostly along its planes
"
# (the vertices renumbered within the chunks); in the builder's order, the level face for face
"$tools/tombuild" "$data/meshes/bunny00.off" -o "$work/kept" -q --stream --keep-order
kept5="$("$tools/tominfo" --json "$work/kept/bunny00.tom" | /usr/bin/python3 -c "import json, sys; print(json.load(sys.stdin)['stream']['chunks'][5]['end_byte'])")"
"$tools/tomextract" "$work/kept/bunny00.tom" --bytes "$kept5" -o "$work/kept-prefix.obj" > /dev/null
check "tombuild --stream --keep-order: a prefix is the ordinary file's level, face for face" cmp <(grep '^f' "$work/kept-prefix.obj") <(grep '^f' "$work/level.obj")
check "and is larger than the default stream" test "$(stat -c %s "$work/kept/bunny00.tom")" -gt "$(stat -c %s "$work/streamed/bunny00.tom")"
check "tomextract --bytes on an ordinary file exits 1 and says why" expect_exit 1 "$tools/tomextract" "$work/plain/bunny00.tom" --bytes 1000 -o "$work/x.obj"
check "(a byte limit applies only to streams)" grep -q "not a streamed .tom file" "$work/stderr"
check "a streamed scene with parts extracts as a .glb" expect_exit 0 "$tools/tomextract" "$work/streamed/spider.tom" --fraction 0.5 -o "$work/spider.glb"
check "a rerun of tombuild --stream finds the streamed outputs up to date" bash -c "'$tools/tombuild' '$data/meshes/bunny00.off' -o '$work/streamed' --stream 2>&1 | grep -q 'up to date'"
# the stream's quantization and chunking are options, recorded in the provenance: a finer growth
# gives more, smaller chunks, fewer position bits a smaller file, and another value converts again
"$tools/tominfo" --json "$work/streamed/bunny00.tom" > "$work/default.json"
"$tools/tombuild" "$data/meshes/bunny00.off" -o "$work/fine" -q --stream --chunk-growth 1.1 --position-bits 11
check "tombuild --stream --chunk-growth 1.1 --position-bits 11 writes more chunks in fewer bytes" /usr/bin/python3 -c "
import json, subprocess
coarse = json.load(open('$work/default.json'))
fine = json.loads(subprocess.run(['$tools/tominfo', '--json', '$work/fine/bunny00.tom'], capture_output=True, check=True).stdout)
a, b = coarse['stream']['chunks'], fine['stream']['chunks']
assert len(b) >= 1.8 * len(a), (len(a), len(b))
assert all(y['triangles'] <= 1.1 * x['triangles'] + 64 for x, y in zip(b, b[1:])), 'a chunk grows past 1.1x'
assert fine['stream']['file_bytes'] < coarse['stream']['file_bytes'], (fine['stream']['file_bytes'], coarse['stream']['file_bytes'])
assert fine['provenance']['options']['stream'] == {'position_bits': 11, 'normal_bits': 8, 'texcoord_bits': 12, 'first_chunk': 0.01, 'chunk_growth': 1.1, 'keep_order': False}, fine['provenance']['options']
"
check "another --chunk-growth converts the file again" bash -c "'$tools/tombuild' '$data/meshes/bunny00.off' -o '$work/fine' --stream --chunk-growth 1.2 --position-bits 11 2>&1 | grep -q '1 of 1 inputs converted'"
check "a stream option without --stream is a usage error" expect_exit 2 "$tools/tombuild" "$data/meshes/bunny00.off" -o "$work/fine" --chunk-growth 1.1
# a textured GLB's embedded image travels in the deferred block, after the mesh's first chunk:
# the first frame does not wait for it, and a prefix before it says what it lacks
"$tools/tombuild" "$data/assimp/glTF2/BoxTextured-glTF-Binary/BoxTextured.glb" -o "$work/streamed" -q --stream
check "tominfo --json places a textured GLB's deferred block after its first chunk" expect_exit 0 "$tools/tominfo" --json "$work/streamed/BoxTextured.tom"
check "(the block follows the first chunk and holds most of the file: the image)" /usr/bin/python3 -c "
import json
s = json.load(open('$work/stdout'))['stream']
d, c = s['deferred'], s['chunks']
assert d['after_chunk'] == 1 and d['begin_byte'] == c[0]['end_byte'] and d['end_byte'] - d['begin_byte'] > 0.5 * s['file_bytes'], (d, c)
open('$work/box-first', 'w').write(str(c[0]['end_byte']))
"
check "tomextract --bytes before the block writes the coarse box" expect_exit 0 "$tools/tomextract" "$work/streamed/BoxTextured.tom" --bytes "$(cat "$work/box-first")" -o "$work/box-first.glb"
check "and warns that it has no embedded images yet" grep -q "BoxTextured.tom: the first $(cat "$work/box-first") bytes end before the deferred sections" "$work/stderr"
head -c 5000 "$work/streamed/bunny00.tom" > "$work/cut.tom"
check "a truncated streamed file exits 1" expect_exit 1 "$tools/tominfo" "$work/cut.tom"
check "naming the file and the truncation" grep -q "cut.tom.*truncated" "$work/stderr"

echo "$passed passed, $fail failed"
[ "$fail" -eq 0 ]
