# shellcheck shell=bash
# Sourced by bench/compare_elastix.sh and bench/compare_peers.sh: the elastix B-spline
# registration of two signed-distance images, the same for every pair (not tuned per pair).
#
# Everything elastix is told is here; the parameter file is written from these values, and each
# can be overridden from the environment (e.g. ELASTIX_ITERATIONS=500). Choices, measured on a
# sphere -> anisotropically stretched ellipsoid pair at levels 5 and 6 (3D):
# - final control-point spacing 4 voxels (4h), reached from 32 voxels by halving per resolution;
# - the bending penalty is needed: with weight 0 the metric keeps decreasing but at the two finest
#   resolutions the points drift along the level sets (mean |T(v) - g(v)| 0.23 of the box against
#   0.014 after the second resolution) and det DT < 0 on thousands of voxels; 1e-6 still folds a
#   few voxels, 3e-6 does not (it is a weight in unit-box lengths: the same for every pair);
# - 250 iterations per resolution: 500 lower the mean residual by a tenth (7.2e-4 -> 6.5e-4 at
#   level 6) at twice the time, with the same ground-truth error;
# - ASGD with automatic step sizes (elastix's default optimizer for B-splines), first-order
#   interpolation of the moving image in the metric (the SDF is smooth; order 3 fared no better).
# 2D images (the figure pairs, at level 9) take the same values per axis.
ELASTIX_PYRAMID=${ELASTIX_PYRAMID:-"8 4 2 1"}              # resolutions: downsampling factor of each (recursive pyramid)
ELASTIX_GRID_SPACING=${ELASTIX_GRID_SPACING:-4}            # final B-spline control-point spacing, voxels of level L
ELASTIX_GRID_SCHEDULE=${ELASTIX_GRID_SCHEDULE:-"8 4 2 1"}  # grid spacing multiplier per resolution
ELASTIX_ITERATIONS=${ELASTIX_ITERATIONS:-250}              # ASGD iterations per resolution
ELASTIX_SAMPLES=${ELASTIX_SAMPLES:-4096}                   # random samples per iteration
ELASTIX_SAMPLER=${ELASTIX_SAMPLER:-RandomCoordinate}       # new samples every iteration
ELASTIX_BENDING=${ELASTIX_BENDING:-3e-6}                   # weight of TransformBendingEnergyPenalty (unit-box lengths); 0: none

# elastix_check: fails (status 1, message on stderr) unless ELASTIX_PYRAMID and
# ELASTIX_GRID_SCHEDULE have one value per resolution; sets ELASTIX_RESOLUTIONS.
elastix_check() {
  local pyr sch
  read -r -a pyr <<<"$ELASTIX_PYRAMID"
  read -r -a sch <<<"$ELASTIX_GRID_SCHEDULE"
  ELASTIX_RESOLUTIONS=${#pyr[@]}
  [ "${#sch[@]}" -eq "$ELASTIX_RESOLUTIONS" ] || {
    echo "ELASTIX_PYRAMID and ELASTIX_GRID_SCHEDULE need one value per resolution" >&2
    return 1
  }
}

# elastix_summary: one line describing the registration, for the scripts' headers.
elastix_summary() {
  echo "B-spline, $ELASTIX_RESOLUTIONS resolutions (recursive pyramid $ELASTIX_PYRAMID)," \
    "final grid spacing $ELASTIX_GRID_SPACING voxels (schedule $ELASTIX_GRID_SCHEDULE)," \
    "AdvancedMeanSquares + $ELASTIX_BENDING x TransformBendingEnergyPenalty, ASGD" \
    "$ELASTIX_ITERATIONS iterations/resolution, $ELASTIX_SAMPLER sampler $ELASTIX_SAMPLES samples"
}

# elastix_parameters DIM FILE: writes the parameter file for DIM-dimensional images.
elastix_parameters() {
  local dim=$1 file=$2
  # each per-resolution factor repeated once per axis
  per_axis() {
    local f i
    for f in $1; do
      for ((i = 0; i < dim; i++)); do printf '%s ' "$f"; done
    done
  }
  {
    echo "// written by bench/accuracy/elastix.sh: B-spline registration of two signed-distance images"
    echo '(FixedInternalImagePixelType "float")'
    echo '(MovingInternalImagePixelType "float")'
    echo "(FixedImageDimension $dim)"
    echo "(MovingImageDimension $dim)"
    echo '(UseDirectionCosines "true")'
    echo "(NumberOfResolutions $ELASTIX_RESOLUTIONS)"
    echo '(FixedImagePyramid "FixedRecursiveImagePyramid")'
    echo '(MovingImagePyramid "MovingRecursiveImagePyramid")'
    echo "(ImagePyramidSchedule $(per_axis "$ELASTIX_PYRAMID"))"
    echo '(Transform "BSplineTransform")'
    echo '(BSplineTransformSplineOrder 3)'
    echo "(FinalGridSpacingInVoxels $(per_axis "$ELASTIX_GRID_SPACING"))"
    echo "(GridSpacingSchedule $(per_axis "$ELASTIX_GRID_SCHEDULE"))"
    echo '(HowToCombineTransforms "Compose")'
    if [ "$ELASTIX_BENDING" = 0 ]; then
      echo '(Registration "MultiResolutionRegistration")'
      echo '(Metric "AdvancedMeanSquares")'
    else
      echo '(Registration "MultiMetricMultiResolutionRegistration")'
      echo '(Metric "AdvancedMeanSquares" "TransformBendingEnergyPenalty")'
      echo '(Metric0Weight 1.0)'
      echo "(Metric1Weight $ELASTIX_BENDING)"
    fi
    echo '(Optimizer "AdaptiveStochasticGradientDescent")'
    echo '(AutomaticParameterEstimation "true")'
    echo '(ASGDParameterEstimationMethod "Original")'
    echo "(MaximumNumberOfIterations $ELASTIX_ITERATIONS)"
    echo "(ImageSampler \"$ELASTIX_SAMPLER\")"
    echo "(NumberOfSpatialSamples $ELASTIX_SAMPLES)"
    echo '(NewSamplesEveryIteration "true")'
    echo '(CheckNumberOfSamples "true")'
    echo '(Interpolator "BSplineInterpolator")'
    echo '(BSplineInterpolationOrder 1)'
    echo '(ResampleInterpolator "FinalBSplineInterpolator")'
    echo '(FinalBSplineInterpolationOrder 1)'
    echo '(Resampler "DefaultResampler")'
    echo '(DefaultPixelValue 0)'
    echo '(WriteResultImage "false")'
    echo '(ResultImageFormat "mhd")'
    echo '(ResultImagePixelType "float")'
    echo '(WriteTransformParametersEachIteration "false")'
    echo '(WriteTransformParametersEachResolution "false")'
    echo '(ShowExactMetricValue "false")'
  } >"$file"
}
