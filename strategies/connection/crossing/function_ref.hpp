/// \file function_ref.hpp
/// A callable passed by reference, not owned, through one indirect call: how the crossing
/// connection's compiled parts take a caller's lambda without being templates. Internal to the
/// crossing connection.
#pragma once

#include <type_traits>
#include <utility>

namespace ndc::crossing_detail {

template <class Signature>
class FunctionRef;

/// A reference to a callable `f` with `f(args...)` convertible to R. It holds `f`'s address:
/// `f` must outlive every call (as a lambda passed down a call does).
template <class R, class... Args>
class FunctionRef<R(Args...)> {
 public:
  template <class F, class = std::enable_if_t<!std::is_same_v<std::decay_t<F>, FunctionRef>>>
  FunctionRef(const F& f)
      : object_(&f), call_([](const void* object, Args... args) -> R {
          return (*static_cast<const F*>(object))(std::forward<Args>(args)...);
        }) {}

  R operator()(Args... args) const { return call_(object_, std::forward<Args>(args)...); }

 private:
  const void* object_;
  R (*call_)(const void*, Args...);
};

}  // namespace ndc::crossing_detail
