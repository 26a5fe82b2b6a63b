#pragma once
/// \file huge_page_allocator.h
/// A std::allocator replacement for the large arrays of acceleration structures and their builds. Large
/// blocks are 2 MiB aligned and marked MADV_HUGEPAGE, so transparent huge pages back them where the
/// kernel allows it ("madvise" mode is Debian's default). Incoherent rays touch nodes and leaves all
/// over tens of MB: with 4 KiB pages nearly every node visit is also a TLB miss (Embree allocates
/// its nodes the same way for the same reason).
#include <cstddef>
#include <cstdlib>
#include <new>
#include <type_traits>
#include <utility>

#if defined(__linux__)
#include <sys/mman.h>
#endif

namespace tessera {

template <class T>
struct HugePageAllocator {
    using value_type = T;
    static constexpr size_t kHugePage = size_t(2) << 20;

    HugePageAllocator() = default;
    template <class U>
    HugePageAllocator(const HugePageAllocator<U>&) noexcept {}

    T* allocate(size_t n) {
        size_t bytes = n * sizeof(T);
        void* p = nullptr;
        if (bytes >= kHugePage) {
            size_t rounded = (bytes + kHugePage - 1) / kHugePage * kHugePage;
            p = std::aligned_alloc(kHugePage, rounded);
#if defined(__linux__) && defined(MADV_HUGEPAGE)
            if (p) madvise(p, rounded, MADV_HUGEPAGE);  // a hint: failure only costs speed
#endif
        } else {
            size_t align = alignof(T) > alignof(std::max_align_t) ? alignof(T) : alignof(std::max_align_t);
            p = std::aligned_alloc(align, (bytes + align - 1) / align * align);
        }
        if (!p) throw std::bad_alloc();
        return static_cast<T*>(p);
    }
    void deallocate(T* p, size_t) noexcept { std::free(p); }
    /// resize() and emplace_back() without arguments default-initialise: no zeroing. Every user
    /// writes its array in full right after, in parallel, and value-initialising first was a
    /// serial pass over tens of MB (with the page faults of first touch): 15–20% of the dragon's
    /// two-thread BVH build.
    template <class U>
    void construct(U* p) noexcept(std::is_nothrow_default_constructible_v<U>) {
        ::new (static_cast<void*>(p)) U;
    }
    template <class U, class... Args>
    void construct(U* p, Args&&... args) {
        ::new (static_cast<void*>(p)) U(std::forward<Args>(args)...);
    }

    template <class U>
    bool operator==(const HugePageAllocator<U>&) const noexcept { return true; }
};

}  // namespace tessera
