# Shared by the reproduction scripts: refine one input with several markings
# and print them side by side. Needs $bisect and $root.

# closure_cost CSV: closure bisections per selected cell over all iterations.
closure_cost() {
  awk -F, 'NR == 1 {for (i = 1; i <= NF; i++) col[$i] = i; next}
           {s += $col["selected"]; b += $col["bisections"]}
           END {printf "%.2f", s ? (b - s) / s : 0}' "$1"
}
json_num() { grep -o "\"$1\":[0-9.e+-]*" | head -n1 | cut -d: -f2; }

# compare_markings INPUT REGION ITERATIONS CLASS_ITERATIONS OUT MARKING...
# Writes OUT/<marking>.vtu/.csv (and the t = 0, 1/2, 1 sections of the first
# marking's mesh for a 4D input) and prints one row per marking.
compare_markings() {
  local input=$1 region=$2 iterations=$3 class_iterations=$4 out=$5
  shift 5
  local first=1 dim slices=()
  dim=$("$bisect" info "$input" | awk '/^dimension:/ {print $2}')
  printf '%-10s %12s %10s %8s %8s %12s %16s %8s\n' marking cells vertices "min q" "max q" \
    "closure/sel" "classes" "seconds"
  for marking in "$@"; do
    slices=()
    ((first && dim == 4)) && slices=(--slices 0,0.5,1)
    local t0=$SECONDS summary classes
    summary=$("$bisect" refine "$input" --region "$region" --iterations "$iterations" \
      --marking "$marking" -o "$out/$marking.vtu" --quality-csv "$out/$marking.csv" \
      "${slices[@]}" --json --quiet --force)
    local secs=$((SECONDS - t0))
    "$bisect" refine "$input" --region "$region" --iterations "$class_iterations" --marking "$marking" \
      -o "$out/$marking-classes.vtu" --quality-csv "$out/$marking-classes.csv" --quiet --force
    classes=$("$bisect" quality "$out/$marking-classes.vtu" --classes | awk -F': *' '/^classes:/ {print $2}')
    rm -f "$out/$marking-classes.vtu" "$out/$marking-classes.csv"
    printf '%-10s %12s %10s %8.4f %8.4f %12s %16s %8s\n' "$marking" "$(json_num cells <<<"$summary")" \
      "$(json_num vertices <<<"$summary")" "$(json_num min_quality <<<"$summary")" \
      "$(json_num max_quality <<<"$summary")" "$(closure_cost "$out/$marking.csv")" \
      "$classes (it $class_iterations)" "$secs"
    first=0
  done
}

# plot_markings TITLE OUT MARKING...: OUT/quality.png from OUT/<marking>.csv.
plot_markings() {
  local title=$1 out=$2
  shift 2
  [[ "${PLOT:-1}" == 0 ]] && return 0
  local csvs=() labels
  for marking in "$@"; do csvs+=("$out/$marking.csv"); done
  labels=$(IFS=,; echo "$*")
  /usr/bin/python3 "$root/scripts/plot_quality.py" "${csvs[@]}" --labels "$labels" --title "$title" \
    -o "$out/quality.png"
}
