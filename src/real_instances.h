/* Instantiates a kernel text for double and float: define SHL_REAL_IMPL as its
 * file name and include this header.  The text is written over REAL, SUFFIX(name)
 * (name_d, name_f), PUBLIC(name) (the public names: name, name_f) and TAB(name)
 * (the factor tables shl__sh_name_d / _f of sh_tables.c).  No include guard: one use per kernel text. */
#define REAL double
#define SUFFIX(name) name##_d
#define PUBLIC(name) name
#define TAB(name) shl__sh_##name##_d
#include SHL_REAL_IMPL
#undef REAL
#undef SUFFIX
#undef PUBLIC
#undef TAB

#define REAL float
#define SUFFIX(name) name##_f
#define PUBLIC(name) name##_f
#define TAB(name) shl__sh_##name##_f
#include SHL_REAL_IMPL
#undef REAL
#undef SUFFIX
#undef PUBLIC
#undef TAB
#undef SHL_REAL_IMPL
