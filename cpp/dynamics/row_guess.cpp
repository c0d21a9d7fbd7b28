// The active-set guesser of RoverSim's bounded rows (row_guess.hpp).
#include "ernest/dynamics/row_guess.hpp"

#include <algorithm>

namespace ernest::dynamics::detail {

void RowGuesser::reset() {
  last_.fill(RowState::Free);
  before_.fill(RowState::Free);
  alternating_ = false;
}

RowStates RowGuesser::first_guess() {
  const bool chatter = alternating_ && before_ != last_;
  alternating_ = false;
  return chatter ? before_ : last_;
}

bool RowGuesser::other_outcome(int attempt, bool rows_held, const RowStates& tried,
                               RowStates& guess) const {
  if (attempt != 1 || rows_held || before_ == last_) return false;
  const RowStates& other = tried == before_ ? last_ : before_;
  if (other == tried) return false;
  guess = other;
  return true;
}

RowStates RowGuesser::next_guess(int attempt, const RowStates& tried, const RowStates& outcome) {
  RowStates guess;
  for (int r = 0; r < kGuessedRowCount; ++r) {
    if (attempt >= kMaxGuesses) {
      guess[r] = tried[r] != RowState::Bounded && outcome[r] != tried[r] ? RowState::Bounded
                                                                          : tried[r];
    } else {
      const bool flipped = (tried[r] == RowState::AtHi && outcome[r] == RowState::AtLo) ||
                           (tried[r] == RowState::AtLo && outcome[r] == RowState::AtHi);
      guess[r] = flipped ? RowState::Free : outcome[r];
    }
  }
  return guess;
}

void RowGuesser::held(const RowStates& guess) {
  alternating_ = guess == before_ && before_ != last_;
}

void RowGuesser::commit(const RowStates& outcome) {
  before_ = last_;
  last_ = outcome;
}

GuessResult RowGuesser::result(bool held, int attempts, const RowStates& tried) {
  const bool some_bounded = std::find(tried.begin(), tried.end(), RowState::Bounded) != tried.end();
  if (held && attempts == 1) return GuessResult::First;
  if (held && !some_bounded) return GuessResult::Later;
  return GuessResult::Pivoted;
}

void RowGuesser::set(const RowStates& last, const RowStates& before, bool alternating) {
  last_ = last;
  before_ = before;
  alternating_ = alternating;
}

}  // namespace ernest::dynamics::detail
