# The CMake package: `cmake --install` of this build into a fresh prefix, then
# tests/downstream (find_package(bisect), bisect::bisect) configured against
# it, built and run; its mesh must pass `bisect check` and continue to refine.
source "$(dirname "$0")/lib.bash"
cd "$WORK"
build=$(dirname "$BISECT")
[[ -f "$build/cmake_install.cmake" ]] || fail "$build is not a CMake build directory"
cmake --install "$build" --prefix "$WORK/prefix" >install.log 2>&1 || { cat install.log; fail "install"; }
for f in include/bisect/bisect.hpp lib/cmake/bisect/bisectConfig.cmake bin/bisect; do
  [[ -e "prefix/$f" ]] || fail "install is missing $f"
done
# Nothing of the Python module goes into a plain install.
! grep -q pybisect install.log || fail "a plain install installed the Python module"
cmake -S "$ROOT/tests/downstream" -B down -DCMAKE_PREFIX_PATH="$WORK/prefix" \
  -DCMAKE_BUILD_TYPE=Release >configure.log 2>&1 || { cat configure.log; fail "configure"; }
cmake --build down >build.log 2>&1 || { cat build.log; fail "build"; }
./down/downstream out.vtu >run.log || { cat run.log; fail "downstream run"; }
grep -q "iteration 4:" run.log || fail "no progress from the callback"
# The installed binary runs from the prefix too (RPATH $ORIGIN/../lib).
expect_exit 0 "$WORK/prefix/bin/bisect" check out.vtu
expect_exit 0 "$WORK/prefix/bin/bisect" info out.vtu
grep -q "bisection state: present" "$WORK/out" || fail "saved mesh has no bisection state"
echo "downstream: $(tail -1 run.log)"
