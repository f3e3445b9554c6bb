// Every member of an aggregate, in declaration order, without a hand-kept list: what a run
// changes (Data) is saved, restored and compared as a whole, so a member added later cannot
// be missed by the checkpoint. The member count comes from aggregate initialisation and the
// members from a structured binding; names come from a FieldNames specialisation whose length
// a static_assert ties to that count.
#pragma once

#include <array>
#include <cstddef>
#include <string_view>
#include <tuple>
#include <type_traits>
#include <utility>
#include <vector>

namespace phymul::fields {

namespace detail {

// Converts to any member type (in unevaluated contexts only).
struct AnyMember {
  template <class T>
  operator T() const;  // NOLINT: implicit by design
};

template <class T, class... Members>
consteval std::size_t count_members() {
  if constexpr (requires { T{std::declval<Members>()..., AnyMember{}}; })
    return count_members<T, Members..., AnyMember>();
  else
    return sizeof...(Members);
}

}  // namespace detail

// Containers the visitors go into element by element.
template <class T>
inline constexpr bool is_vector = false;
template <class T, class A>
inline constexpr bool is_vector<std::vector<T, A>> = true;
template <class T>
inline constexpr bool is_array = false;
template <class T, std::size_t N>
inline constexpr bool is_array<std::array<T, N>> = true;

// Number of members of the aggregate T (no base classes, no arrays of C type as members).
template <class T>
inline constexpr std::size_t count = detail::count_members<std::remove_cv_t<T>>();

// The members' names, in order: specialise for each aggregate that is visited.
template <class T>
struct FieldNames;

// The members of t as a tuple of references, in declaration order.
template <class T>
auto tie_members(T& t) {
  constexpr std::size_t n = count<std::remove_cv_t<T>>;
  static_assert(n >= 1 && n <= 24, "fields::tie_members binds 1 to 24 members");
#define PHYMUL_FIELDS_BIND(N, ...) \
  if constexpr (n == N) {          \
    auto& [__VA_ARGS__] = t;       \
    return std::tie(__VA_ARGS__);  \
  } else
  PHYMUL_FIELDS_BIND(1, a0)
  PHYMUL_FIELDS_BIND(2, a0, a1)
  PHYMUL_FIELDS_BIND(3, a0, a1, a2)
  PHYMUL_FIELDS_BIND(4, a0, a1, a2, a3)
  PHYMUL_FIELDS_BIND(5, a0, a1, a2, a3, a4)
  PHYMUL_FIELDS_BIND(6, a0, a1, a2, a3, a4, a5)
  PHYMUL_FIELDS_BIND(7, a0, a1, a2, a3, a4, a5, a6)
  PHYMUL_FIELDS_BIND(8, a0, a1, a2, a3, a4, a5, a6, a7)
  PHYMUL_FIELDS_BIND(9, a0, a1, a2, a3, a4, a5, a6, a7, a8)
  PHYMUL_FIELDS_BIND(10, a0, a1, a2, a3, a4, a5, a6, a7, a8, a9)
  PHYMUL_FIELDS_BIND(11, a0, a1, a2, a3, a4, a5, a6, a7, a8, a9, a10)
  PHYMUL_FIELDS_BIND(12, a0, a1, a2, a3, a4, a5, a6, a7, a8, a9, a10, a11)
  PHYMUL_FIELDS_BIND(13, a0, a1, a2, a3, a4, a5, a6, a7, a8, a9, a10, a11, a12)
  PHYMUL_FIELDS_BIND(14, a0, a1, a2, a3, a4, a5, a6, a7, a8, a9, a10, a11, a12, a13)
  PHYMUL_FIELDS_BIND(15, a0, a1, a2, a3, a4, a5, a6, a7, a8, a9, a10, a11, a12, a13, a14)
  PHYMUL_FIELDS_BIND(16, a0, a1, a2, a3, a4, a5, a6, a7, a8, a9, a10, a11, a12, a13, a14, a15)
  PHYMUL_FIELDS_BIND(17, a0, a1, a2, a3, a4, a5, a6, a7, a8, a9, a10, a11, a12, a13, a14, a15, a16)
  PHYMUL_FIELDS_BIND(18, a0, a1, a2, a3, a4, a5, a6, a7, a8, a9, a10, a11, a12, a13, a14, a15, a16,
                     a17)
  PHYMUL_FIELDS_BIND(19, a0, a1, a2, a3, a4, a5, a6, a7, a8, a9, a10, a11, a12, a13, a14, a15, a16,
                     a17, a18)
  PHYMUL_FIELDS_BIND(20, a0, a1, a2, a3, a4, a5, a6, a7, a8, a9, a10, a11, a12, a13, a14, a15, a16,
                     a17, a18, a19)
  PHYMUL_FIELDS_BIND(21, a0, a1, a2, a3, a4, a5, a6, a7, a8, a9, a10, a11, a12, a13, a14, a15, a16,
                     a17, a18, a19, a20)
  PHYMUL_FIELDS_BIND(22, a0, a1, a2, a3, a4, a5, a6, a7, a8, a9, a10, a11, a12, a13, a14, a15, a16,
                     a17, a18, a19, a20, a21)
  PHYMUL_FIELDS_BIND(23, a0, a1, a2, a3, a4, a5, a6, a7, a8, a9, a10, a11, a12, a13, a14, a15, a16,
                     a17, a18, a19, a20, a21, a22)
  PHYMUL_FIELDS_BIND(24, a0, a1, a2, a3, a4, a5, a6, a7, a8, a9, a10, a11, a12, a13, a14, a15, a16,
                     a17, a18, a19, a20, a21, a22, a23)
  return std::tuple<>{};
#undef PHYMUL_FIELDS_BIND
}

template <class T>
constexpr const auto& names_of() {
  using Plain = std::remove_cv_t<T>;
  constexpr auto& names = FieldNames<Plain>::names;
  static_assert(std::size(names) == count<Plain>,
                "FieldNames<T> must name every member of T, in order: a member was added or "
                "removed without its name");
  return names;
}

// Calls visit(name, member) for each member of t, in declaration order.
template <class T, class Visit>
void for_each(T& t, Visit&& visit) {
  const auto& names = names_of<T>();
  std::apply(
      [&](auto&... members) {
        std::size_t i = 0;
        (visit(std::string_view(names[i++]), members), ...);
      },
      tie_members(t));
}

// Calls visit(name, member of a, the same member of b) for each member, in order.
template <class T, class U, class Visit>
void for_each_pair(T& a, U& b, Visit&& visit) {
  static_assert(std::is_same_v<std::remove_cv_t<T>, std::remove_cv_t<U>>);
  const auto& names = names_of<T>();
  auto ta = tie_members(a);
  auto tb = tie_members(b);
  [&]<std::size_t... I>(std::index_sequence<I...>) {
    (visit(std::string_view(names[I]), std::get<I>(ta), std::get<I>(tb)), ...);
  }
  (std::make_index_sequence<count<std::remove_cv_t<T>>>{});
}

}  // namespace phymul::fields
