# Shared set-up for scripts/demo, scripts/test and friends (sourced, not run).
# Installs the Debian packages the package needs (only those missing), keeps the catkin
# workspace beside the repository in <repo>_ws (or $ATTITUDE_PLANNER_WS) and keeps ROS_HOME and
# logs inside it.
set -euo pipefail

REPO_DIR="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
# The workspace lives outside the package: rosrun and roslaunch search the package directory
# recursively (find -L), so a workspace inside it, linking back to it, is a file-system loop and
# offers every build product as a rosrun executable.
WS_DIR="${ATTITUDE_PLANNER_WS:-${REPO_DIR}_ws}"
# Studies and test executables: in the build tree, not in devel/lib/attitude_planner (rosrun's
# libexec), which holds only the nodes and the command-line tools (TOOL_DIR).
study_bin_dir() { echo "$WS_DIR/build/attitude_planner/bin"; }
tool_dir() { echo "$WS_DIR/devel/lib/attitude_planner"; }
BUILD_TYPE="${BUILD_TYPE:-Release}"

# Debian bookworm ships ROS 1 (ros_comm 1.15); rosdep cannot reach its index, so list apt packages.
DEBIAN_PACKAGES=(
  build-essential cmake catkin python3-catkin-pkg python3-rospkg
  libroscpp-dev libroslib-dev ros-message-generation ros-message-runtime
  libstd-msgs-dev libgeometry-msgs-dev libvisualization-msgs-dev libactionlib-msgs-dev
  libtf2-ros-dev libtf2-geometry-msgs-dev tf2-tools libactionlib-dev python3-actionlib
  librosbag-dev python3-rosbag librostest-dev python3-rostest rosbash rosout python3-roslaunch
  libeigen3-dev libnlopt-cxx-dev libyaml-cpp-dev libboost-math-dev libgtest-dev
  coinor-libipopt-dev
  python3-numpy python3-matplotlib python3-yaml valgrind
  ros-std-msgs ros-geometry-msgs ros-actionlib-msgs ros-visualization-msgs
  python3-visualization-msgs python3-rostopic python3-rosservice
  libnav-msgs-dev ros-nav-msgs python3-nav-msgs libtf2-msgs-dev
  libdiagnostic-msgs-dev ros-diagnostic-msgs python3-diagnostic-msgs
  libsensor-msgs-dev ros-sensor-msgs python3-sensor-msgs
  pybind11-dev python3-pybind11 python3-dev python3-setuptools
  python3-distributed python3-dask python3-tqdm
)

log() { printf '[attitude_planner] %s\n' "$*" >&2; }

install_debian_packages() {
  local missing=()
  for p in "$@"; do
    dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
  done
  if [ ${#missing[@]} -eq 0 ]; then return 0; fi
  log "installing Debian packages: ${missing[*]}"
  local sudo=""
  [ "$(id -u)" -eq 0 ] || sudo="sudo"
  export DEBIAN_FRONTEND=noninteractive
  $sudo apt-get update -qq
  $sudo apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
}

# The pyenv python3 on PATH has no ROS modules: pin the system interpreter for catkin and rostest.
setup_ros_env() {
  export PYENV_VERSION=system
  export PATH="/usr/bin:$PATH"
  export ROS_HOME="$WS_DIR/ros_home"
  export ROS_LOG_DIR="$ROS_HOME/log"
  mkdir -p "$ROS_LOG_DIR"
}

# A workspace left inside the repository by an older version of these scripts links back to the
# package (a find loop on every rosrun): its link is removed, the rest is left to delete by hand.
remove_in_repo_workspace_links() {
  local old
  for old in "$REPO_DIR"/.ws "$REPO_DIR"/.ws-asan "$REPO_DIR"/.ws-tsan; do
    if [ -L "$old/src/attitude_planner" ]; then
      rm "$old/src/attitude_planner"
      log "removed $old/src/attitude_planner (a link back to the package); $old is obsolete: rm -rf it"
    fi
  done
}

build_workspace() {
  setup_ros_env
  remove_in_repo_workspace_links
  mkdir -p "$WS_DIR/src"
  # The repository root is the package; the workspace (outside it) sees it through a symlink.
  [ -L "$WS_DIR/src/attitude_planner" ] || ln -sfn "$REPO_DIR" "$WS_DIR/src/attitude_planner"
  log "building ($BUILD_TYPE) in $WS_DIR"
  # ccache, where installed, serves unchanged files from its cache (other worktrees included).
  local launcher=()
  if command -v ccache >/dev/null; then
    launcher=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache)
    export CCACHE_BASEDIR="${CCACHE_BASEDIR:-$(dirname "$REPO_DIR")}"
  fi
  (cd "$WS_DIR" && catkin_make -DCMAKE_BUILD_TYPE="$BUILD_TYPE" "${launcher[@]}" \
      -DPYTHON_EXECUTABLE=/usr/bin/python3 -DCATKIN_ENABLE_TESTING=ON -j"$(nproc)" "$@" >"$WS_DIR/build.log" 2>&1) \
    || { tail -n 60 "$WS_DIR/build.log"; log "build failed (full log: $WS_DIR/build.log)"; return 1; }
  source_workspace
}

source_workspace() {
  setup_ros_env
  set +u
  # shellcheck disable=SC1091
  source "$WS_DIR/devel/setup.bash"
  set -u
  export ROS_HOME="$WS_DIR/ros_home"
  export ROS_LOG_DIR="$ROS_HOME/log"
}
