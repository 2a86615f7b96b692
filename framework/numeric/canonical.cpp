// The canonical form of a program (canonical.hpp): a stack machine over sparse polynomials with
// exact decimal coefficients, run once over the program, then the collected monomials written
// back as a program.
#include "framework/numeric/canonical.hpp"

#include <boost/multiprecision/cpp_int.hpp>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <map>
#include <numeric>
#include <string>
#include <utility>
#include <vector>

#include "framework/numeric/interval.hpp"

namespace ndc {

namespace {

using BigInt = boost::multiprecision::cpp_int;

/// Thrown inside the expansion when a limit is passed or a coefficient cannot stay exact.
struct GiveUp {};

/// Largest |decimal exponent| a coefficient may have (beyond double's range either way).
constexpr long kMaxExponent10 = 100000;

/// An exact decimal m * 10^e, normalised: m has no trailing zero digit (e = 0 when m = 0).
struct Decimal {
  BigInt m;
  long e = 0;

  void normalise() {
    if (m == 0) {
      e = 0;
      return;
    }
    while (m % 10 == 0) {
      m /= 10;
      ++e;
    }
    if (std::labs(e) > kMaxExponent10) throw GiveUp{};
  }
};

/// Decimal digits of |m| (an upper bound by one).
std::size_t digits(const BigInt& m) {
  if (m == 0) return 1;
  return static_cast<std::size_t>(static_cast<double>(msb(abs(m))) * 0.30103) + 1;
}

/// b^p (p >= 0).
BigInt bigPower(long b, long p) { return boost::multiprecision::pow(BigInt(b), unsigned(p)); }

/// The limits and the work spent so far.
struct Budget {
  CanonicalLimits limits;
  std::size_t work = 0;

  void spend(std::size_t units) {
    work += units;
    if (work > limits.maxWork) throw GiveUp{};
  }
  void checkDigits(const BigInt& m) const {
    if (digits(m) > limits.maxDigits) throw GiveUp{};
  }
};

Decimal add(const Decimal& a, const Decimal& b, const Budget& budget) {
  if (a.m == 0) return b;
  if (b.m == 0) return a;
  const long e = std::min(a.e, b.e);
  if (std::max(a.e, b.e) - e > static_cast<long>(budget.limits.maxDigits)) throw GiveUp{};
  Decimal r{a.m * bigPower(10, a.e - e) + b.m * bigPower(10, b.e - e), e};
  r.normalise();
  budget.checkDigits(r.m);
  return r;
}

Decimal multiply(const Decimal& a, const Decimal& b, const Budget& budget) {
  Decimal r{a.m * b.m, a.e + b.e};
  r.normalise();
  budget.checkDigits(r.m);
  return r;
}

/// The decimal a literal's text spells: digits [. digits] [(e|E) [+|-] digits].
Decimal parseLiteral(const std::string& text) {
  const std::size_t exp = text.find_first_of("eE");
  const std::string mantissa = text.substr(0, exp);
  long e = 0;
  if (exp != std::string::npos) {
    const std::string power = text.substr(exp + 1);
    if (power.size() > 8) throw GiveUp{};  // |e| beyond any double: leave the program alone
    e = std::strtol(power.c_str(), nullptr, 10);
  }
  std::string digitsOnly;
  const std::size_t point = mantissa.find('.');
  for (char c : mantissa)
    if (c != '.') digitsOnly += c;
  if (point != std::string::npos) e -= static_cast<long>(mantissa.size() - point - 1);
  // Leading zeros would make the string an octal number to cpp_int.
  const std::size_t first = digitsOnly.find_first_not_of('0');
  Decimal d{first == std::string::npos ? BigInt(0) : BigInt(digitsOnly.substr(first)), e};
  d.normalise();
  return d;
}

/// The decimal of a double, exactly (a double is m 2^q, and 2^-1 = 5 * 10^-1).
Decimal exactDouble(double v) {
  int q = 0;
  const double f = std::frexp(std::fabs(v), &q);
  // f * 2^53 is an integer below 2^53.
  BigInt m = static_cast<long long>(std::ldexp(f, 53));
  q -= 53;
  Decimal d{m, 0};
  if (q >= 0) {
    d.m <<= q;
  } else {
    d.m *= bigPower(5, -q);
    d.e = q;
  }
  if (v < 0) d.m = -d.m;
  d.normalise();
  return d;
}

/// 1 / d, when it is a finite decimal: |m| = 2^a 5^b, so 1 / m = 5^a 2^b / 10^(a + b).
Decimal reciprocal(const Decimal& d) {
  if (d.m == 0) throw GiveUp{};
  BigInt rest = abs(d.m);
  long twos = 0, fives = 0;
  while (rest % 2 == 0) {
    rest /= 2;
    ++twos;
  }
  while (rest % 5 == 0) {
    rest /= 5;
    ++fives;
  }
  if (rest != 1) throw GiveUp{};
  const BigInt m = bigPower(5, twos) * bigPower(2, fives);
  Decimal r{d.m < 0 ? BigInt(-m) : m, -d.e - twos - fives};
  r.normalise();
  return r;
}

using Exponents = std::vector<int>;
/// A sparse polynomial: exponents to nonzero coefficient.
using Polynomial = std::map<Exponents, Decimal>;

/// a += c x^e, dropping the term when it cancels.
void addTerm(Polynomial& a, Exponents e, const Decimal& c, const Budget& budget) {
  auto [it, inserted] = a.try_emplace(std::move(e), c);
  if (inserted) {
    if (a.size() > budget.limits.maxTerms) throw GiveUp{};
    return;
  }
  it->second = add(it->second, c, budget);
  if (it->second.m == 0) a.erase(it);
}

/// a += sign * b.
void accumulate(Polynomial& a, const Polynomial& b, bool negate, Budget& budget) {
  budget.spend(b.size());
  for (const auto& [exponents, c] : b) {
    Decimal term = c;
    if (negate) term.m = -term.m;
    addTerm(a, exponents, term, budget);
  }
}

Polynomial product(const Polynomial& a, const Polynomial& b, Budget& budget) {
  budget.spend(a.size() * b.size());
  Polynomial r;
  for (const auto& [ea, ca] : a)
    for (const auto& [eb, cb] : b) {
      Exponents e(ea.size());
      for (std::size_t j = 0; j < e.size(); ++j) {
        e[j] = ea[j] + eb[j];
        if (e[j] > 1000000) throw GiveUp{};
      }
      addTerm(r, std::move(e), multiply(ca, cb, budget), budget);
    }
  return r;
}

Polynomial power(const Polynomial& base, int p, int dim, Budget& budget) {
  Polynomial result{{Exponents(static_cast<std::size_t>(dim), 0), Decimal{1, 0}}};
  Polynomial square = base;
  for (; p > 0; p >>= 1) {
    if (p & 1) result = product(result, square, budget);
    if (p > 1) square = product(square, square, budget);
  }
  return result;
}

/// Runs `tape` over sparse polynomials.
Polynomial expand(const Tape& tape, Budget& budget) {
  using K = TapeOp::Kind;
  const auto dim = static_cast<std::size_t>(tape.dim());
  std::vector<Polynomial> stack;
  for (const TapeOp& op : tape.ops()) {
    switch (op.kind) {
      case K::kConstant: {
        const TapeConstant& c = tape.constants()[static_cast<std::size_t>(op.arg)];
        Decimal d = c.literal.empty() ? exactDouble(c.value) : parseLiteral(c.literal);
        Polynomial p;
        if (d.m != 0) p.emplace(Exponents(dim, 0), std::move(d));
        stack.push_back(std::move(p));
        break;
      }
      case K::kVariable: {
        Exponents e(dim, 0);
        e[static_cast<std::size_t>(op.arg)] = 1;
        stack.push_back(Polynomial{{std::move(e), Decimal{1, 0}}});
        break;
      }
      case K::kLeaf:
        throw GiveUp{};
      case K::kNeg:
        for (auto& [e, c] : stack.back()) c.m = -c.m;
        break;
      case K::kPow:
        stack.back() = power(stack.back(), op.arg, static_cast<int>(dim), budget);
        break;
      default: {
        Polynomial right = std::move(stack.back());
        stack.pop_back();
        Polynomial& left = stack.back();
        if (op.kind == K::kAdd || op.kind == K::kSub) {
          // Merge the smaller into the larger: a long sum costs its terms, not their square.
          const bool negate = op.kind == K::kSub;
          if (left.size() >= right.size()) {
            accumulate(left, right, negate, budget);
          } else {
            if (negate)
              for (auto& [e, c] : right) c.m = -c.m;
            accumulate(right, left, false, budget);
            left = std::move(right);
          }
        } else if (op.kind == K::kMul) {
          left = product(left, right, budget);
        } else {  // kDiv: the divisor is a constant polynomial
          if (right.size() != 1 ||
              std::any_of(right.begin()->first.begin(), right.begin()->first.end(),
                          [](int a) { return a != 0; }))
            throw GiveUp{};
          const Polynomial inverse{{right.begin()->first, reciprocal(right.begin()->second)}};
          left = product(left, inverse, budget);
        }
      }
    }
  }
  return std::move(stack.back());
}

/// The positive literal of |d|: its digits, then `e` and the exponent when it is not 0.
std::string literalOf(const Decimal& d) {
  std::string text = BigInt(abs(d.m)).str();
  if (d.e != 0) text += "e" + std::to_string(d.e);
  return text;
}

/// Monomial order: higher total degree first, then lexicographically larger exponents.
bool before(const Exponents& a, const Exponents& b) {
  const int da = std::accumulate(a.begin(), a.end(), 0),
            db = std::accumulate(b.begin(), b.end(), 0);
  return da != db ? da > db : a > b;
}

/// Appends c x^e with |c| (its sign is left to the caller).
void pushMonomial(Tape& tape, const Exponents& e, const Decimal& c) {
  using K = TapeOp::Kind;
  bool any = false;
  const bool unit = c.e == 0 && abs(c.m) == 1;
  const bool constant = std::all_of(e.begin(), e.end(), [](int a) { return a == 0; });
  if (!unit || constant) {
    const std::string literal = literalOf(c);
    const double value = std::strtod(literal.c_str(), nullptr);
    if (!std::isfinite(value) || (value == 0 && c.m != 0)) throw GiveUp{};
    tape.pushConstant(TapeConstant::fromLiteral(literal));
    any = true;
  }
  for (std::size_t j = 0; j < e.size(); ++j) {
    if (e[j] == 0) continue;
    tape.push({K::kVariable, static_cast<int>(j)});
    if (e[j] > 1) tape.push({K::kPow, e[j]});
    if (any) tape.push({K::kMul, 0});
    any = true;
  }
}

}  // namespace

std::optional<Tape> canonicalTape(const Tape& tape, const CanonicalLimits& limits) {
  if (!tape.leaves().empty()) return std::nullopt;
  Budget budget{limits};
  Polynomial polynomial;
  try {
    polynomial = expand(tape, budget);
  } catch (const GiveUp&) {
    return std::nullopt;
  }
  // The monomials in a fixed order, each with its sign.
  std::vector<std::pair<Exponents, Decimal>> terms(polynomial.begin(), polynomial.end());
  std::sort(terms.begin(), terms.end(),
            [](const auto& a, const auto& b) { return before(a.first, b.first); });
  Tape out(tape.dim());
  if (terms.empty()) {
    out.pushConstant(TapeConstant::fromLiteral("0"));
    return out;
  }
  try {
    for (std::size_t i = 0; i < terms.size(); ++i) {
      const bool negative = terms[i].second.m < 0;
      pushMonomial(out, terms[i].first, terms[i].second);
      if (i == 0 && negative) out.push({TapeOp::Kind::kNeg, 0});
      if (i > 0) out.push({negative ? TapeOp::Kind::kSub : TapeOp::Kind::kAdd, 0});
    }
  } catch (const GiveUp&) {
    return std::nullopt;
  }
  return out;
}

CanonicalLimits canonicalLimitsFor(std::size_t ops) {
  CanonicalLimits limits;
  limits.maxTerms = ops;
  limits.maxWork = 16 * ops + 4096;
  return limits;
}

}  // namespace ndc
