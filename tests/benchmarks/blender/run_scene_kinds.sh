#!/usr/bin/env bash
# Solo against Blender Cycles on every scene kind: for each kind, the exported scene, solo's
# converged reference and runs (fixed Sobol 1/4/16/64 spp, the default adaptive settings and fixed
# sampling at the adaptive run's mean spp), Cycles at a few sample counts, then one table: CPU
# seconds to equal error for both renderers and their ratio, and adaptive against fixed sampling
# at equal samples. Needs a release build (export_blender_scene, solo) and `blender` on the PATH
# (Blender 3.4.1; not installed by tools/setup.sh).
#
#   tests/benchmarks/blender/run_scene_kinds.sh [WORK_DIR]      (default /tmp/solo_scene_kinds)
#
# Environment: EXPORT and SOLO (the binaries; build/release by default), SIZE (240x135),
# REFERENCE_SPP (1024), CYCLES_SAMPLES (32,128,512), THREADS (2), KINDS (a space-separated
# subset of the kind names below), SOLO_RUNS_AGAIN=1 (repeat only solo's adaptive and
# equal-sample runs against the references already in WORK_DIR, e.g. after a change to the
# sampler; Cycles' renders are kept). A kind whose reference or Cycles log exists in WORK_DIR is
# not rendered again. SOLO_RELATIVE_ERROR and SOLO_ADAPTIVE_RULE=threshold reach the exporter's
# default adaptive run. About 12 minutes on 2 cores.
#
#   ERROR_SOURCES=1 tests/benchmarks/blender/run_scene_kinds.sh [WORK_DIR]
#
# instead splits solo's error on each kind by its source (export_blender_scene error-sources:
# direct light, light scattered twice or more, the worst 0.1 % of the pixels) and prints that
# table; no Cycles, no Blender. Environment: ERROR_REFERENCE_SPP (512 per component),
# ERROR_SPP (16), ERROR_SEEDS (8), ADAPTIVE_SEEDS (2). About 15 minutes on 2 cores.
set -euo pipefail

ROOT=$(cd "$(dirname "$0")/../../.." && pwd)
EXPORT=${EXPORT:-$ROOT/build/release/tests/benchmarks/export_blender_scene}
SOLO=${SOLO:-$ROOT/build/release/tools/solo}
CYCLES_SCRIPT=$ROOT/tests/benchmarks/blender/render_cycles.py
WORK=${1:-/tmp/solo_scene_kinds}
SIZE=${SIZE:-240x135}
REFERENCE_SPP=${REFERENCE_SPP:-1024}
CYCLES_SAMPLES=${CYCLES_SAMPLES:-32,128,512}
THREADS=${THREADS:-2}
mkdir -p "$WORK"

# The synthetic streets the kinds are made from: NAME SEED VARIANT SIZE. The embedded default
# scene (data/default/scene.json) is `solo synth --seed 1` at 960x540.
synth() {
  [ -f "$WORK/streets/$1/scene.json" ] || "$SOLO" synth --seed "$2" --variant "$3" --size "$4" -o "$WORK/streets/$1" > /dev/null
}
synth seed4 4 default 960x540
synth seed2-wide-sky 2 wide-sky 960x540
synth seed3-1080p 3 default 1920x1080

# NAME SCENE CYCLES (1 = rendered by Cycles too). rough keeps the roughness map, which the
# Cycles script cannot express (it renders Lambertian surfaces): solo only. windows drops the
# street lights (the windows and the cars' lights stay), headlights every emitter.
DEFAULT_SCENE=$ROOT/data/default/scene.json
KIND_TABLE="
default pipeline:$DEFAULT_SCENE 1
synth-seed4 pipeline:$WORK/streets/seed4/scene.json 1
synth-seed2-wide-sky pipeline:$WORK/streets/seed2-wide-sky/scene.json 1
default-rough rough:$DEFAULT_SCENE 0
street-1080p-compact-lamps pipeline:$WORK/streets/seed3-1080p/scene.json 1
windows-no-street-lights windows:$DEFAULT_SCENE 1
headlights-only headlights:$DEFAULT_SCENE 1
"

# Where solo's error comes from, kind by kind (docs/rendering.md, "Where the error comes from").
if [ "${ERROR_SOURCES:-0}" = 1 ]; then
  rows=""
  while read -r name spec cycles; do
    [ -n "$name" ] || continue
    if [ -n "${KINDS:-}" ] && [[ " $KINDS " != *" $name "* ]]; then continue; fi
    dir=$WORK/kinds/$name/error_sources
    mkdir -p "$dir"
    echo "== $name ($spec): error sources" >&2
    "$EXPORT" error-sources "$spec" "$dir" "$SIZE" "${ERROR_REFERENCE_SPP:-512}" "${ERROR_SPP:-16}" \
      "${ERROR_SEEDS:-8}" "${ADAPTIVE_SEEDS:-2}" > "$dir/error_sources.log"
    rows+="| $name | $(sed -n 's/^row: //p' "$dir/error_sources.log") |"$'\n'
  done <<< "$KIND_TABLE"
  echo
  echo "| scene kind | indirect share of the light | fixed ${ERROR_SPP:-16} spp: relative RMSE | direct | indirect" \
    "| cross term | worst 0.1 % of pixels (their indirect share) | default adaptive: spp, relative RMSE, worst 0.1 % |"
  echo "|---|---|---|---|---|---|---|---|"
  printf '%s' "$rows"
  exit 0
fi

while read -r name spec cycles; do
  [ -n "$name" ] || continue
  if [ -n "${KINDS:-}" ] && [[ " $KINDS " != *" $name "* ]]; then continue; fi
  scene=$spec
  dir=$WORK/kinds/$name
  mkdir -p "$dir"
  echo "== $name ($scene)" >&2
  if [ ! -f "$dir/solo_reference.exr" ]; then
    "$EXPORT" export "$scene" "$dir" "$SIZE" "$REFERENCE_SPP" sobol > "$dir/export.log"
  elif [ "${SOLO_RUNS_AGAIN:-0}" = 1 ]; then
    "$EXPORT" runs "$scene" "$dir" "$SIZE" - sobol adaptive > "$dir/runs.log"
  fi
  if [ "$cycles" = 1 ]; then
    [ -f "$dir/cycles.log" ] || blender -b --factory-startup -P "$CYCLES_SCRIPT" -- "$dir/scene.json" \
      "$dir/cycles_{n}.exr" --samples "$CYCLES_SAMPLES" --threads "$THREADS" > "$dir/cycles.log" 2>&1
    for n in ${CYCLES_SAMPLES//,/ }; do
      echo "samples $n $("$EXPORT" compare "$dir" "$dir/cycles_$n.exr" | head -1)"
    done > "$dir/cycles_compare.log"
  fi
done <<< "$KIND_TABLE"

# The tables. Cycles' error follows e = k / sqrt(n) (k: the median of e sqrt(n) over its
# renders); its CPU seconds for n samples are its first render's (sync, BVH and samples) plus
# the per-sample slope between its two largest renders for the samples beyond the first's.
python3 - "$WORK" "$KIND_TABLE" <<'EOF'
import csv, os, re, statistics, sys

work, table = sys.argv[1], sys.argv[2]
kinds = [line.split() for line in table.strip().splitlines()]
kinds_wanted = os.environ.get("KINDS", "").split()

def solo_runs(d):
    rows = {}
    for f in ("solo_runs.csv", "solo_runs_again.csv"):
        p = os.path.join(d, f)
        if os.path.exists(p):
            for r in csv.DictReader(open(p)):
                rows[r["settings"]] = r
    return rows

def reference_noise(d):
    p = os.path.join(d, "export.log")
    m = re.search(r"reference relative noise \(two halves\): (\S+)", open(p).read()) if os.path.exists(p) else None
    return float(m.group(1)) if m else 0.0

# An error measured against the reference holds the reference's own noise (independent of the
# image's): the image's error is what remains.
def corrected(e, noise):
    return max(e * e - noise * noise, 0.0) ** 0.5

def cycles_model(d, noise):
    p, q = os.path.join(d, "cycles.log"), os.path.join(d, "cycles_compare.log")
    if not (os.path.exists(p) and os.path.exists(q)):
        return None
    cpu = {int(m.group(1)): float(m.group(2)) for m in
           re.finditer(r"cycles: samples (\d+) threads \d+ render_seconds \S+ cpu_seconds (\S+)", open(p).read())}
    err = {int(m.group(1)): corrected(float(m.group(2)), noise) for m in
           re.finditer(r"samples (\d+) relative_rmse (\S+)", open(q).read())}
    n = sorted(cpu)
    ratio = {int(m.group(1)): float(m.group(2)) for m in
             re.finditer(r"samples (\d+) relative_rmse \S+ mean_ratio (\S+)", open(q).read())}
    if err[n[-1]] > 0.7 * err[n[0]]:
        # The 1/sqrt law fails: Cycles converges to another image than solo's reference.
        return None, "Cycles' error flat at %.3f from %d to %d samples (mean ratio %.3f): not comparable" % (
            err[n[-1]], n[0], n[-1], ratio.get(n[-1], float("nan")))
    slope = (cpu[n[-1]] - cpu[n[-2]]) / (n[-1] - n[-2])
    k = statistics.median(err[s] * s ** 0.5 for s in n)
    seconds = lambda e: cpu[n[0]] + slope * max(0.0, (k / e) ** 2 - n[0])
    points = " / ".join("%d: %.3f in %.1f s, mean %.3f" % (s, err[s], cpu[s], ratio.get(s, float("nan"))) for s in n)
    return seconds, k, slope, points

print("\nSolo and Cycles: CPU seconds to equal error (relative RMSE of Y against solo's reference, its noise taken out)\n")
print("| scene kind | reference noise | Cycles k, CPU s per sample | solo fixed 16: error, CPU s, Cycles CPU s, ratio "
      "| solo fixed 64 | solo default adaptive (mean spp) |")
print("|---|---|---|---|---|---|")
adaptive_rows = []
for name, spec, cycles in kinds:
    if kinds_wanted and name not in kinds_wanted:
        continue
    d = os.path.join(work, "kinds", name)
    runs = solo_runs(d)
    if not runs:
        continue
    noise = reference_noise(d)
    model = cycles_model(d, noise) if cycles == "1" else None
    note = "not comparable (roughness)" if cycles != "1" else ""
    if model and model[0] is None:
        model, note = None, model[1]
    cells = []
    for label in ("fixed 16 sobol", "fixed 64 sobol", "default adaptive sobol"):
        r = runs.get(label)
        if r is None:
            cells.append("-")
            continue
        e, t = corrected(float(r["relative_rmse"]), noise), float(r["cpu_seconds"])
        cell = "%.3f, %.1f s" % (e, t)
        if label.startswith("default"):
            cell += " (%.0f spp)" % float(r["spp_mean"])
        if model:
            c = model[0](e)
            cell += ", %.0f s, **1/%.0f**" % (c, c / t)
        cells.append(cell)
    cyc = "k %.2f, %.3f s" % (model[1], model[2]) if model else note
    print("| %s | %.3f | %s | %s |" % (name, noise, cyc, " | ".join(cells)))
    a, f = runs.get("default adaptive sobol"), runs.get("fixed at adaptive mean sobol")
    if a and f:
        adaptive_rows.append((name, a, f))
    if model:
        print("|  | Cycles renders: %s | | | | |" % model[3])

print("\nAdaptive against fixed sampling at equal samples (Sobol)\n")
print("| scene kind | adaptive mean spp | adaptive error, CPU s | fixed at that spp: error, CPU s | error ratio |")
print("|---|---|---|---|---|")
for name, a, f in adaptive_rows:
    noise = reference_noise(os.path.join(work, "kinds", name))
    ea, ef = corrected(float(a["relative_rmse"]), noise), corrected(float(f["relative_rmse"]), noise)
    print("| %s | %.1f | %.3f, %.1f s | %.3f, %.1f s | %.2f |" % (name, float(a["spp_mean"]), ea, float(a["cpu_seconds"]),
                                                           ef, float(f["cpu_seconds"]), ea / ef if ef > 0 else float("nan")))
EOF
