// The active-set guesser of RoverSim's bounded rows on its own (cpp/dynamics/row_guess.hpp): which
// guess a step tries first, second and next, and that the attempts end.
#include <gtest/gtest.h>

#include <algorithm>
#include <random>

#include "ernest/dynamics/row_guess.hpp"

using namespace ernest::dynamics;
using namespace ernest::dynamics::detail;

namespace {

RowStates all(RowState s) {
  RowStates r;
  r.fill(s);
  return r;
}

RowStates with(RowStates r, int row, RowState s) {
  r[row] = s;
  return r;
}

}  // namespace

TEST(RowGuess, StatusOfARowFollowsItsLawAgainstItsBounds) {
  EXPECT_EQ(status_of(2.0, 1.0), RowState::AtHi);
  EXPECT_EQ(status_of(1.0, 1.0), RowState::AtHi);  // at the bound: applied as the bound's force
  EXPECT_EQ(status_of(-1.0, 1.0), RowState::AtLo);
  EXPECT_EQ(status_of(0.5, 1.0), RowState::Free);
  EXPECT_EQ(status_of(0.0, 0.0), RowState::AtHi);  // a zero bound: never free
}

TEST(RowGuess, ABoundedRowAlwaysHoldsAGuessedOneOnlyWhereItsLawAgrees) {
  for (RowState out : {RowState::Free, RowState::AtHi, RowState::AtLo}) {
    EXPECT_TRUE(guess_holds(RowState::Bounded, out));
    EXPECT_TRUE(guess_holds(out, out));
  }
  EXPECT_FALSE(guess_holds(RowState::Free, RowState::AtHi));
  EXPECT_FALSE(guess_holds(RowState::AtLo, RowState::AtHi));
}

TEST(RowGuess, AllBoundedIsExplicitAndBoundsEveryRow) {
  const RowModes b = RowModes::all_bounded();
  EXPECT_FALSE(b.guessed());
  for (int r = 0; r < kGuessedRowCount; ++r) EXPECT_EQ(b[r], RowState::Bounded);
  const RowStates g = with(all(RowState::Free), 3, RowState::AtLo);
  const RowModes m = RowModes::guess(g);
  EXPECT_TRUE(m.guessed());
  EXPECT_EQ(m[3], RowState::AtLo);
  EXPECT_EQ(m[4], RowState::Free);
}

TEST(RowGuess, FirstGuessIsTheLastOutcomeUnlessTheOutcomesAlternate) {
  RowGuesser g;
  g.reset();
  EXPECT_EQ(g.first_guess(), all(RowState::Free));  // placed at rest: every row inside
  const RowStates a = with(all(RowState::Free), 0, RowState::AtHi);
  const RowStates b = with(all(RowState::Free), 0, RowState::AtLo);
  g.commit(a);
  g.commit(b);  // last b, before a
  EXPECT_EQ(g.first_guess(), b);
  // A step whose guess b failed held on a (the outcome two steps back): a chatter. Its outcome is
  // a again, so the next step starts from the one two steps back, b.
  g.held(a);
  EXPECT_TRUE(g.alternating());
  g.commit(a);
  EXPECT_EQ(g.first_guess(), b);
  EXPECT_FALSE(g.alternating());  // first_guess() ends the flag
  // Holding on the last outcome is no chatter.
  g.held(g.last());
  EXPECT_FALSE(g.alternating());
}

TEST(RowGuess, SecondGuessIsTheOtherOfTheLastTwoOutcomesAfterAFailedFirstAttempt) {
  RowGuesser g;
  const RowStates a = with(all(RowState::Free), 7, RowState::AtHi);
  const RowStates b = with(all(RowState::Free), 7, RowState::AtLo);
  g.set(b, a, false);
  RowStates guess = all(RowState::Bounded);
  ASSERT_TRUE(g.other_outcome(1, false, b, guess));
  EXPECT_EQ(guess, a);
  ASSERT_TRUE(g.other_outcome(1, false, a, guess));
  EXPECT_EQ(guess, b);
  EXPECT_FALSE(g.other_outcome(2, false, b, guess));  // only after the first attempt
  EXPECT_FALSE(g.other_outcome(1, true, b, guess));   // the rows held (the obstacles did not)
  g.set(a, a, false);
  EXPECT_FALSE(g.other_outcome(1, false, a, guess));  // no second outcome to try
}

TEST(RowGuess, NextGuessIsTheOutcomeWithFlippedRowsFreedThenFailedRowsBounded) {
  RowStates tried = all(RowState::Free);
  tried[0] = RowState::AtHi;
  tried[1] = RowState::AtLo;
  tried[2] = RowState::AtHi;
  RowStates out = tried;
  out[0] = RowState::AtLo;  // jumped from one bound to the other: most likely between them
  out[1] = RowState::AtHi;
  out[2] = RowState::Free;
  out[3] = RowState::AtHi;
  const RowStates second = RowGuesser::next_guess(1, tried, out);
  EXPECT_EQ(second[0], RowState::Free);
  EXPECT_EQ(second[1], RowState::Free);
  EXPECT_EQ(second[2], RowState::Free);
  EXPECT_EQ(second[3], RowState::AtHi);
  EXPECT_EQ(second[4], RowState::Free);
  const RowStates later = RowGuesser::next_guess(RowGuesser::kMaxGuesses, tried, out);
  for (int r = 0; r < 4; ++r) EXPECT_EQ(later[r], RowState::Bounded) << r;  // its guess failed
  EXPECT_EQ(later[4], RowState::Free);                                      // held: kept
}

TEST(RowGuess, AttemptsEndWhateverTheLawsSay) {
  // Adversarial outcomes (random, never the guess) cannot keep a step going: from kMaxGuesses on
  // every attempt bounds each failed row, and bounded rows always hold.
  std::mt19937 rng(1);
  for (int trial = 0; trial < 200; ++trial) {
    RowStates guess = all(RowState::Free);
    int attempt = 0;
    bool held = false;
    while (!held) {
      ASSERT_LT(attempt, RowGuesser::kMaxAttempts) << trial;
      ++attempt;
      RowStates out;
      held = true;
      for (int r = 0; r < kGuessedRowCount; ++r) {
        out[r] = static_cast<RowState>(rng() % 3);
        if (trial % 2 == 0 && out[r] == guess[r]) out[r] = static_cast<RowState>((static_cast<int>(out[r]) + 1) % 3);
        held = held && guess_holds(guess[r], out[r]);
      }
      if (!held) guess = RowGuesser::next_guess(attempt, guess, out);
    }
  }
}

TEST(RowGuess, ResultSaysWhichGuessHeld) {
  const RowStates free = all(RowState::Free);
  const RowStates some_bounded = with(free, 5, RowState::Bounded);
  EXPECT_EQ(RowGuesser::result(true, 1, free), GuessResult::First);
  EXPECT_EQ(RowGuesser::result(true, 2, free), GuessResult::Later);
  EXPECT_EQ(RowGuesser::result(true, 4, some_bounded), GuessResult::Pivoted);
  EXPECT_EQ(RowGuesser::result(false, 1, free), GuessResult::Pivoted);
}
