# The layers' direction (README, "Source map"): core <- measure <- engine <-
# io <- mpi; engine <- region, tools; region <- mpi. The linker enforces it for symbols (each layer
# is a shared library linked with --no-undefined against the layers below it
# only); this checks the includes: no file of a layer includes a header of a
# layer above it or beside it.
source "$(dirname "$0")/lib.bash"
cd "$ROOT"
# The layer of each public header in include/bisect/.
declare -A layer_of=(
  [mesh]=core [error]=core [text]=core
  [check]=measure [measure]=measure [threads]=measure
  [mark]=engine [refine]=engine [driver]=engine [indicator]=engine [coarsen]=engine
  [io]=io [state]=io [output]=io
  [region]=region
  [colour]=tools [extrude]=tools [slice]=tools [generate]=tools [bisect]=all
  [distributed]=mpi
)
# What each layer may include.
declare -A allowed=(
  [core]="core"
  [measure]="core measure"
  [engine]="core measure engine"
  [io]="core measure engine io"
  [region]="core measure engine region"
  [tools]="core measure engine tools"
  [mpi]="core measure engine io region mpi"
)
bad=0
check_file() { # FILE LAYER
  local file=$1 layer=$2 inc l
  while read -r inc; do
    case $inc in
      bisect/*.hpp) l=${layer_of[$(basename "$inc" .hpp)]:-unknown} ;;
      core/* | measure/* | engine/* | io/* | region/* | tools/* | mpi/*) l=${inc%%/*} ;;
      *) continue ;;
    esac
    if [[ " ${allowed[$layer]} " != *" $l "* ]]; then
      echo "layers: $file ($layer) includes $inc ($l)" >&2
      bad=1
    fi
  done < <(sed -n 's/^#include "\(.*\)".*/\1/p' "$file")
}
n=0
for layer in core measure engine io region tools mpi; do
  for f in src/$layer/*.cpp src/$layer/*.hpp; do
    [[ -e $f ]] || continue
    check_file "$f" "$layer"
    n=$((n + 1))
  done
done
for h in include/bisect/*.hpp; do
  l=${layer_of[$(basename "$h" .hpp)]:-unknown}
  [[ $l == unknown ]] && { echo "layers: $h has no layer in this test" >&2; bad=1; continue; }
  [[ $l == all ]] && continue
  check_file "$h" "$l"
  n=$((n + 1))
done
((bad == 0)) || fail "a layer includes a header above it"
echo "layers: $n files, every include goes down"
