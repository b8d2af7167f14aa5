#!/usr/bin/env bash
# A new user's first hour, scripted: clone the repository into a temporary folder, run
# the README's two set-up commands exactly as written (extracted from README.md, not
# copied here), run every example, and check what a newcomer would see:
#   * no output of any command contains "Traceback";
#   * every example prints its key numbers against their references ("check: ...");
#   * every example writes its VTU, PNG and JSON;
#   * --overwrite into a folder of the user's (notes, a subfolder, the scene itself,
#     --out .) replaces only the run's own files, twice over;
#   * the tunnel's picture is framed on the tunnel, its VTU carries the FE reference.
#
# Usage: bash scripts/newcomer.sh [REPOSITORY]   (default: this checkout; KEEP=1 keeps
# the clone and every example's outputs, to open the pictures)
# Takes about 10 minutes on 2 cores (the test suite is most of it). Exit 0 when all is
# well; otherwise the failures are listed and the exit status is 1.
set -uo pipefail

repo="${1:-$(cd "$(dirname "$0")/.." && pwd)}"
work="$(mktemp -d)"
trap 'if [ -n "${KEEP:-}" ]; then echo "kept $work"; else rm -rf "$work"; fi' EXIT
log="$work/log"
mkdir -p "$log"
failures=()

fail() { failures+=("$1"); echo "FAIL: $1"; }

git clone -q "$repo" "$work/dvstatic" || { echo "cannot clone $repo"; exit 1; }
cd "$work/dvstatic" || exit 1

# the first two bash blocks of the README's set-up section: install + main job, tests
# (the optional PETSc build that follows them is not a newcomer's first step)
mapfile -t commands < <(
    awk '/^## Set-up/{on=1} /^## /&&!/^## Set-up/{on=0} on&&/^```bash/{b=1;next} on&&/^```/{b=0} b' README.md |
        head -2
)
if [ "${#commands[@]}" -ne 2 ]; then
    fail "the README's set-up section has ${#commands[@]} commands, expected 2"
fi
for i in "${!commands[@]}"; do
    echo "== README command $((i + 1)): ${commands[$i]}"
    start=$SECONDS
    if ! bash -c "${commands[$i]}" >"$log/readme$i.txt" 2>&1; then
        fail "README command $((i + 1)) exited non-zero (see its output below)"
        tail -20 "$log/readme$i.txt"
    fi
    echo "   $((SECONDS - start)) s; last line: $(tail -1 "$log/readme$i.txt")"
done

export MPLBACKEND=Agg
for scene in examples/*.toml; do
    name="$(basename "$scene" .toml)"
    out="$work/out/$name"
    start=$SECONDS
    .venv/bin/dvstatic run "$scene" --out "$out" >"$log/$name.txt" 2>&1
    code=$?
    echo "== $name: exit $code, $((SECONDS - start)) s"
    grep -E "^ *check: " "$log/$name.txt" | sed 's/^ */   /'
    [ "$code" -eq 0 ] || fail "$name exited with $code"
    grep -q "check: " "$log/$name.txt" || fail "$name prints no key number against a reference"
    if grep -q "^\[fracture\]" "$scene"; then
        for f in "${name}_fracture.json" "${name}_curve.png" "${name}_crack.png" \
            "${name}_fracture/${name}.pvd"; do
            [ -s "$out/$f" ] || fail "$name wrote no $f"
        done
    else
        for ext in vtu png json; do
            [ -s "$out/$name.$ext" ] || fail "$name wrote no $name.$ext"
        done
    fi
done

# the pictures frame what matters: the tunnel (2 % of its body) is framed, the whole
# beam is shown; the tunnel's VTU carries the FE reference beside the lattice
view_of() { .venv/bin/python -c "import json,sys; print(json.load(open(sys.argv[1]))['picture']['view'])" "$1"; }
tunnel_view="$(view_of "$work/out/tunnel/tunnel.json" 2>/dev/null)"
[ "$tunnel_view" = "[-5.0, 5.0, -5.0, 5.0]" ] || fail "the tunnel picture is not framed on the tunnel ($tunnel_view)"
.venv/bin/python -c "import meshio,sys; d=meshio.read(sys.argv[1]).point_data; sys.exit('fe_displacement' not in d)" \
    "$work/out/tunnel/tunnel.vtu" || fail "the tunnel VTU has no FE reference fields"
echo "== pictures: tunnel framed on $tunnel_view; look at them in $work/out (kept with KEEP=1)"

# data loss: a folder with foreign files, a subfolder and the scene inside it, two runs
p="$work/mine"
mkdir -p "$p/sub" && echo x >"$p/notes.txt" && echo y >"$p/sub/keep.dat"
cp examples/uniaxial.toml "$p/"
for run in 1 2; do
    .venv/bin/dvstatic run "$p/uniaxial.toml" --out "$p" --overwrite -q >"$log/mine$run.txt" 2>&1 ||
        fail "run $run into a folder of the user's exited non-zero"
done
(cd "$p" && ../dvstatic/.venv/bin/dvstatic run uniaxial.toml --out . --overwrite -q >"$log/dot.txt" 2>&1) ||
    fail "--out . --overwrite exited non-zero"
for f in notes.txt sub/keep.dat uniaxial.toml uniaxial.json uniaxial.png uniaxial.vtu; do
    [ -s "$p/$f" ] || fail "after --overwrite into the user's folder, $f is missing"
done
echo "== --overwrite into a folder of the user's: kept $(cd "$p" && ls -A | tr '\n' ' ')"

if grep -l "Traceback" "$log"/*.txt >/dev/null 2>&1; then
    for f in $(grep -l "Traceback" "$log"/*.txt); do fail "Traceback in $(basename "$f")"; done
fi

if [ "${#failures[@]}" -eq 0 ]; then
    echo "newcomer run: all well (README commands, ${#commands[@]}; examples, $(ls examples/*.toml | wc -l))"
    exit 0
fi
echo "newcomer run: ${#failures[@]} failure(s):"
printf '  %s\n' "${failures[@]}"
exit 1
