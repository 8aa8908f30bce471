#pragma once
// Where the code a step runs through lies. At a robot's pace (a sleep between steps) a step finds
// little of its code in the caches and less of it in the TLB: under a VM's nested paging a code
// page the TLB lost costs a page walk of up to two dozen loads before the first instruction on it
// runs. So the functions an observed step runs beside the manager's are kept together, and what
// few steps need is kept apart from them (docs/performance.md, "Serving live to Foxglove").

#if defined(__GNUC__)
/// A function every observed step runs: placed with the others like it (the compilers' .text.hot,
/// which the linker puts together), so that they share a page or two instead of one each.
#define ARBITER_EVERY_STEP __attribute__((hot))
/// Kept out of line: the code around it stays short, and a step that does not need it does not
/// run through its lines.
#define ARBITER_OUT_OF_LINE __attribute__((noinline))
/// Out of line and placed apart (.text.unlikely): what few steps need.
#define ARBITER_SELDOM __attribute__((noinline, cold))
/// Not exported from the library: a call to it from another of the library's files is direct,
/// where one to an exported function goes through the PLT (an indirect jump through the GOT, a
/// cold line and a dependent load at a robot's pace).
#define ARBITER_LIBRARY_LOCAL __attribute__((visibility("hidden")))
#else
#define ARBITER_EVERY_STEP
#define ARBITER_OUT_OF_LINE
#define ARBITER_SELDOM
#define ARBITER_LIBRARY_LOCAL
#endif
