"""Force–torque processing, elevation sampling, the 45-value observation and the reward of seed 004
§4.2–4.3. The implementation is C++ (``ernest_cpp._core.sensing``), shared with the onboard runtime.
"""

from ._core.sensing import (  # noqa: F401  (re-exports)
    ACTION_SIZE,
    ELEVATION_SAMPLES,
    OBSERVATION_CLIP,
    OBSERVATION_INDEX,
    OBSERVATION_LAYOUT_VERSION,
    OBSERVATION_SIZE,
    ActionLimits,
    ElevationSampler,
    ElevationSamplingOptions,
    FtsFilterOptions,
    FtsProcessor,
    GridHeightSource,
    HeightSource,
    ObservationInputs,
    ObservationScales,
    PathLine,
    RewardTerms,
    RewardWeights,
    action_to_command,
    build_observation,
    command_to_action,
    compute_reward,
    fill_line,
    observation_names,
)

#: Slices of the force–torque block, for noise injection (sensor-major: FL, FR, RL, RR x
#: Fx, Fy, Fz, Tx, Ty, Tz).
FTS_SLICE = slice(OBSERVATION_INDEX["fts"], OBSERVATION_INDEX["fts"] + 24)
FORCE_INDICES = [OBSERVATION_INDEX["fts"] + 6 * s + a for s in range(4) for a in range(3)]
TORQUE_INDICES = [OBSERVATION_INDEX["fts"] + 6 * s + a for s in range(4) for a in range(3, 6)]
