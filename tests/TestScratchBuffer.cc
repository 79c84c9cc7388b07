/// @file TestScratchBuffer.cc
#include <vdbmatch/ScratchBuffer.h>

#include <gtest/gtest.h>

#include <vector>

using vdbmatch::detail::ScratchBuffer;

TEST(ScratchBuffer, ALeaseGetsBackTheMemoryOfThePreviousOne)
{
    ScratchBuffer<std::vector<double>> buffer;
    const double* first = nullptr;
    {
        ScratchBuffer<std::vector<double>>::Lease lease(buffer);
        EXPECT_TRUE(lease.reused());
        lease->assign(1000, 1.5);
        first = lease->data();
    }
    ScratchBuffer<std::vector<double>>::Lease again(buffer);
    ASSERT_EQ(again->size(), 1000u);
    EXPECT_EQ(again->data(), first);
    EXPECT_EQ((*again)[999], 1.5);
}

TEST(ScratchBuffer, ASecondLeaseWhileTheFirstIsOutGetsItsOwnValue)
{
    ScratchBuffer<std::vector<double>> buffer;
    {
        ScratchBuffer<std::vector<double>>::Lease a(buffer);
        a->assign(10, 2.0);
        ScratchBuffer<std::vector<double>>::Lease b(buffer);
        EXPECT_FALSE(b.reused());
        EXPECT_TRUE(b->empty());
        b->assign(20, 3.0); // dropped with b: the kept value stays a's
    }
    ScratchBuffer<std::vector<double>>::Lease c(buffer);
    ASSERT_EQ(c->size(), 10u);
    EXPECT_EQ((*c)[0], 2.0);
}
