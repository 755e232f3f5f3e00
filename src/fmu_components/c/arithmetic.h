/* The same arithmetic in the same order as the Python flavour, whatever flags a host
   compiles the sources with (fmpy compile: CMake's Release flags): never fuse a*b + c into
   one rounding. The build passes -ffp-contract=off as well. Included first by every file
   that computes the model. */
#ifndef ARITHMETIC_H
#define ARITHMETIC_H

#if defined(__clang__)
#pragma STDC FP_CONTRACT OFF
#elif defined(__GNUC__)
#pragma GCC optimize("fp-contract=off")
#elif defined(_MSC_VER)
#pragma fp_contract(off)
#endif

#endif
