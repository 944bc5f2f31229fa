# Sourced by reproduce.sh and blind-all-folds.sh: the peers a user would otherwise pick,
# as `desal eval` methods, when they are set up here. Reads $peers (the peers' home, as
# ../shared/peers/setup.sh makes it), $scape and $work (where CGAL's mesh goes); appends
# to $methods CGAL Lindstrom-Turk (an external mesh) and MeshLab plain and with saliency
# (through $DESAL_PYTHON, else python3, when it has pymeshlab); sets $have_meshlab.
if [ -x "$peers/cgal_simplify" ]; then
  # 4996 faces = 2500 vertices on SCAPE's closed genus-0 template, the methods' target.
  "$peers/cgal_simplify" "$scape/mesh000.ply" "$work/cgal-lt-2500.off" 4996 lt 1 > /dev/null
  methods="$methods,external:cgal-lt=$work/cgal-lt-2500.off"
else
  echo "note: no CGAL driver at $peers; running without the cgal-lt column" >&2
fi
python=${DESAL_PYTHON:-python3}
have_meshlab=""
if "$python" -c "import pymeshlab" 2>/dev/null; then
  export DESAL_PYTHON="$python"
  methods="$methods,meshlab,meshlab-saliency"
  have_meshlab=1
else
  echo "note: $python has no pymeshlab; running without the meshlab columns" >&2
fi
