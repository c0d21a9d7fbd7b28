// The active-set guesser of RoverSim's bounded constraint rows (drive torque limits, the soil's
// shear and compaction caps, the soil's normal force; rover_step.cpp explains why they are
// guessed). Internal to cpp/dynamics, no ODE: what a guess is, where a row's law puts it, and
// which guess to try next. rover_rows.cpp / rover_rigid.cpp emit and check the rows of a guess;
// rover_step.cpp runs the attempts.
#pragma once

#include <array>
#include <cstdint>

#include "ernest/dynamics/rover_sim.hpp"

namespace ernest::dynamics::detail {

using RowStates = std::array<RowState, kGuessedRowCount>;

/// Where a soft row's law lambda = u puts it for bounds +-bound.
inline RowState status_of(double u, double bound) {
  return u >= bound ? RowState::AtHi : (u <= -bound ? RowState::AtLo : RowState::Free);
}

/// Whether a row emitted as `guess` held, its law having put it at `outcome`: a bounded row always
/// holds (ODE solved it with its bounds), a guessed one only where its law agrees.
inline bool guess_holds(RowState guess, RowState outcome) {
  return guess == RowState::Bounded || guess == outcome;
}

/// The rows of one attempt at a step: a guess per row, or every row with its bounds (the last
/// resort, and the only mode when SimOptions::guess_active_set is off). Cheap to copy (a view of
/// the guess array, which must outlive it).
class RowModes {
 public:
  static RowModes all_bounded() { return RowModes(nullptr); }
  static RowModes guess(const RowStates& states) { return RowModes(states.data()); }
  /// false: every row bounded (all_bounded()).
  bool guessed() const { return states_ != nullptr; }
  RowState operator[](int row) const { return states_ ? states_[row] : RowState::Bounded; }

 private:
  explicit RowModes(const RowState* states) : states_(states) {}
  const RowState* states_;
};

/// How a step's guesses fared (SolverStats::first_guess / later_guess / pivoted).
enum class GuessResult { First, Later, Pivoted };

/// The guessed rows' outcomes of the last two steps and the choice of guesses from them. A step
/// tries in turn: the last step's outcome (first_guess()); the outcome two steps back (a period-2
/// chatter, e.g. a stuck wheel's v_x changing sign every step, defeats the first; once it held it
/// goes first); then where the last attempt's laws put the rows (next_guess()). After kMaxGuesses
/// wrong guesses every row whose guess failed is bounded, attempt after attempt: each adds at
/// least one bounded row, so a step ends after at most kMaxGuesses + kGuessedRowCount attempts.
class RowGuesser {
 public:
  static constexpr int kMaxGuesses = 3;  // guesses of a step before failing rows are bounded
  static constexpr int kMaxAttempts = kMaxGuesses + kGuessedRowCount;

  /// Every row inside its bounds, no history (a rover placed at rest).
  void reset();
  /// The first guess of a step; ends the chatter flag of the last step.
  RowStates first_guess();
  /// After a failed first attempt (attempt 1) whose guessed rows (not the obstacles) failed: the
  /// other of the last two outcomes, if they differ and it was not the one tried. Returns whether
  /// `guess` was set to it.
  bool other_outcome(int attempt, bool rows_held, const RowStates& tried, RowStates& guess) const;
  /// The guess after attempt `attempt` (1-based) tried `tried` and the rows' laws put them at
  /// `outcome`: the outcome (a row that jumped from one bound to the other, its velocity having
  /// changed sign within the step, most likely between them: free); from kMaxGuesses on, every
  /// failed row bounded instead.
  static RowStates next_guess(int attempt, const RowStates& tried, const RowStates& outcome);
  /// A guess held: remembers whether it was the outcome two steps back (a chatter).
  void held(const RowStates& guess);
  /// The step is accepted with these outcomes: they become the next step's guesses.
  void commit(const RowStates& outcome);
  /// Classifies a finished step (held: a guess held; attempts: how many; tried: the last one).
  static GuessResult result(bool held, int attempts, const RowStates& tried);

  const RowStates& last() const { return last_; }
  const RowStates& before() const { return before_; }
  bool alternating() const { return alternating_; }
  /// Snapshot/restore: the state exactly as last(), before() and alternating() give it.
  void set(const RowStates& last, const RowStates& before, bool alternating);

 private:
  RowStates last_{}, before_{};  // outcomes of the last and the second-to-last step
  bool alternating_ = false;     // the last step held on before_: outcomes alternate
};

}  // namespace ernest::dynamics::detail
